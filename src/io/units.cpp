#include "io/units.hpp"

#include <fmt/format.h>

#include <array>
#include <cctype>
#include <charconv>
#include <cmath>
#include <stdexcept>
#include <system_error>

namespace phymul::io {

namespace {

constexpr std::array kDimensions{
    DimensionInfo{Dimension::none, "number", "a number", "", ""},
    DimensionInfo{Dimension::length, "length", "a length", "m", "m, cm, mm"},
    DimensionInfo{Dimension::time, "time", "a time", "s", "s, ms, min"},
    DimensionInfo{Dimension::mass, "mass", "a mass", "kg", "kg, g, mg"},
    DimensionInfo{Dimension::force, "force", "a force", "N", "N, mN, kN"},
    DimensionInfo{Dimension::stiffness, "stiffness", "a stiffness", "N/m", "N/m, N/mm, kN/m"},
    DimensionInfo{Dimension::pressure, "pressure", "a pressure", "Pa", "Pa, kPa, mmHg"},
    DimensionInfo{Dimension::density, "density", "a density", "kg/m^3", "kg/m^3, g/cm^3, g/mL"},
    DimensionInfo{Dimension::acceleration, "acceleration", "an acceleration", "m/s^2", "m/s^2, g0"},
    DimensionInfo{Dimension::rate, "rate", "a rate", "1/s", "1/s, Hz"},
    DimensionInfo{Dimension::volume, "volume", "a volume", "m^3", "m^3, L, mL"},
    DimensionInfo{Dimension::angle, "angle", "an angle", "rad", "rad, deg"},
};

constexpr std::array kUnits{
    Unit{"m", Dimension::length, 1, 1},
    Unit{"cm", Dimension::length, 1, 1e2},
    Unit{"mm", Dimension::length, 1, 1e3},
    Unit{"um", Dimension::length, 1, 1e6},
    Unit{"\u00b5m", Dimension::length, 1, 1e6},  // micro sign, as typed on most keyboards
    Unit{"s", Dimension::time, 1, 1},
    Unit{"ms", Dimension::time, 1, 1e3},
    Unit{"us", Dimension::time, 1, 1e6},
    Unit{"min", Dimension::time, 60, 1},
    Unit{"h", Dimension::time, 3600, 1},
    Unit{"kg", Dimension::mass, 1, 1},
    Unit{"g", Dimension::mass, 1, 1e3},
    Unit{"mg", Dimension::mass, 1, 1e6},
    Unit{"N", Dimension::force, 1, 1},
    Unit{"mN", Dimension::force, 1, 1e3},
    Unit{"kN", Dimension::force, 1e3, 1},
    Unit{"N/m", Dimension::stiffness, 1, 1},
    Unit{"mN/m", Dimension::stiffness, 1, 1e3},
    Unit{"N/mm", Dimension::stiffness, 1e3, 1},
    Unit{"kN/m", Dimension::stiffness, 1e3, 1},
    Unit{"Pa", Dimension::pressure, 1, 1},
    Unit{"kPa", Dimension::pressure, 1e3, 1},
    Unit{"MPa", Dimension::pressure, 1e6, 1},
    Unit{"GPa", Dimension::pressure, 1e9, 1},
    Unit{"mmHg", Dimension::pressure, 133.322387415, 1},  // conventional millimetre of mercury
    Unit{"cmH2O", Dimension::pressure, 98.0665, 1},
    Unit{"kg/m^3", Dimension::density, 1, 1},
    Unit{"g/cm^3", Dimension::density, 1e3, 1},
    Unit{"g/mL", Dimension::density, 1e3, 1},
    Unit{"kg/L", Dimension::density, 1e3, 1},
    Unit{"m/s^2", Dimension::acceleration, 1, 1},
    Unit{"g0", Dimension::acceleration, 9.80665, 1},  // standard gravity
    Unit{"1/s", Dimension::rate, 1, 1},
    Unit{"Hz", Dimension::rate, 1, 1},
    Unit{"m^3", Dimension::volume, 1, 1},
    Unit{"L", Dimension::volume, 1, 1e3},
    Unit{"mL", Dimension::volume, 1, 1e6},
    Unit{"cm^3", Dimension::volume, 1, 1e6},
    Unit{"mm^3", Dimension::volume, 1, 1e9},
    Unit{"rad", Dimension::angle, 1, 1},
    Unit{"deg", Dimension::angle, 3.14159265358979323846, 180},  // "90 deg": pi/2 exactly
};

std::string_view trim(std::string_view s) {
  const auto first = s.find_first_not_of(" \t\r\n");
  if (first == std::string_view::npos) return {};
  const auto last = s.find_last_not_of(" \t\r\n");
  return s.substr(first, last - first + 1);
}

bool is_digit(char c) { return c >= '0' && c <= '9'; }

size_t skip_digits(std::string_view s, size_t i) {
  while (i < s.size() && is_digit(s[i])) ++i;
  return i;
}

// Length of the leading decimal number ([+-]digits[.digits][e[+-]digits]), 0 if none.
// Written by hand because strtod/from_chars also accept "inf", "nan" and hex floats.
size_t scan_number(std::string_view s) {
  size_t i = 0;
  if (i < s.size() && (s[i] == '+' || s[i] == '-')) ++i;
  const size_t int_end = skip_digits(s, i);
  size_t end = int_end;
  bool digits = int_end > i;
  if (end < s.size() && s[end] == '.') {
    const size_t frac_end = skip_digits(s, end + 1);
    digits = digits || frac_end > end + 1;
    end = frac_end;
  }
  if (!digits) return 0;
  if (end < s.size() && (s[end] == 'e' || s[end] == 'E')) {
    size_t j = end + 1;
    if (j < s.size() && (s[j] == '+' || s[j] == '-')) ++j;
    const size_t exp_end = skip_digits(s, j);
    if (exp_end > j) end = exp_end;  // "2e" alone leaves the 'e' to the unit
  }
  return end;
}

// YAML's ".nan", ".inf", "-.Inf" and the C spellings, with or without a unit after them.
bool names_non_finite(std::string_view s) {
  size_t i = 0;
  if (i < s.size() && (s[i] == '+' || s[i] == '-')) ++i;
  if (i < s.size() && s[i] == '.') ++i;
  std::string word;
  while (i < s.size() && std::isalpha(static_cast<unsigned char>(s[i])))
    word += char(std::tolower(static_cast<unsigned char>(s[i++])));
  return word == "nan" || word == "inf" || word == "infinity";
}

std::string expects(std::string_view field, Dimension dimension) {
  return fmt::format("{} expects {}", field, expected_text(dimension));
}

std::optional<double> read_number(std::string_view digits) {
  if (!digits.empty() && digits.front() == '+') digits.remove_prefix(1);
  double value = 0.0;
  const auto [ptr, ec] = std::from_chars(digits.data(), digits.data() + digits.size(), value);
  if (ec != std::errc{} || ptr != digits.data() + digits.size()) return std::nullopt;
  return value;
}

// Checks the unit of a number; returns an error message or "" when it fits.
std::string unit_error(std::string_view unit_text, Dimension dimension, std::string_view field) {
  const Unit* unit = find_unit(unit_text);
  if (dimension == Dimension::none)
    return fmt::format("{} takes a plain number without a unit, got '{}'", field, unit_text);
  if (unit == nullptr)
    return fmt::format("{} has an unknown unit '{}' ({} units: {})", field, unit_text,
                       dimension_info(dimension).name, unit_list(dimension));
  if (unit->dimension != dimension)
    return fmt::format("{}, got '{}'", expects(field, dimension), unit_text);
  return {};
}

QuantityResult failure(std::string message) { return {std::nullopt, std::move(message)}; }

}  // namespace

std::span<const DimensionInfo> dimension_table() { return kDimensions; }
std::span<const Unit> unit_table() { return kUnits; }

const DimensionInfo& dimension_info(Dimension dimension) {
  for (const auto& info : kDimensions)
    if (info.dimension == dimension) return info;
  throw std::logic_error("dimension missing from the dimension table");
}

const Unit* find_unit(std::string_view symbol) {
  for (const auto& unit : kUnits)
    if (unit.symbol == symbol) return &unit;
  return nullptr;
}

std::string expected_text(Dimension dimension) {
  const auto& info = dimension_info(dimension);
  if (dimension == Dimension::none) return "a number";
  return fmt::format("{} ({}, ...)", info.noun, info.examples);
}

std::string unit_list(Dimension dimension) {
  std::string out;
  for (const auto& unit : kUnits) {
    if (unit.dimension != dimension) continue;
    if (!out.empty()) out += ", ";
    out += unit.symbol;
  }
  return out;
}

std::string format_si(double value, Dimension dimension) {
  const auto si = dimension_info(dimension).si;
  return si.empty() ? fmt::format("{}", value) : fmt::format("{} {}", value, si);
}

QuantityResult parse_quantity(std::string_view text, Dimension dimension, std::string_view field) {
  text = trim(text);
  if (text.empty()) return failure(expects(field, dimension) + ", got nothing");
  if (names_non_finite(text))
    return failure(fmt::format("{} must be a finite number (got '{}')", field, text));
  const size_t length = scan_number(text);
  if (length == 0) return failure(fmt::format("{}, got '{}'", expects(field, dimension), text));

  const auto number = read_number(text.substr(0, length));
  if (!number)
    return failure(fmt::format("{} is out of the representable range (got '{}')", field, text));
  const std::string_view unit_text = trim(text.substr(length));
  double value = *number;
  if (!unit_text.empty()) {
    if (auto error = unit_error(unit_text, dimension, field); !error.empty())
      return failure(std::move(error));
    const Unit& unit = *find_unit(unit_text);
    value = value * unit.scale / unit.divisor;
  }
  if (!std::isfinite(value))
    return failure(fmt::format("{} is out of the representable range (got '{}')", field, text));
  return {value, {}};
}

}  // namespace phymul::io
