// Physical units of scene quantities: "4 mm", "15.3 kPa", "9.81" (SI when no unit is given).
#pragma once

#include <optional>
#include <span>
#include <string>
#include <string_view>

namespace phymul::io {

enum class Dimension {
  none,  // a plain number
  length,
  time,
  mass,
  force,
  stiffness,
  pressure,
  density,
  acceleration,
  rate,
  volume,
  angle,
};

struct DimensionInfo {
  Dimension dimension;
  std::string_view name;      // "time"
  std::string_view noun;      // "a time", used in "'duration' expects a time ..."
  std::string_view si;        // SI symbol, "" for a plain number
  std::string_view examples;  // a few units for messages, "s, ms, min"
};

struct Unit {
  std::string_view symbol;
  Dimension dimension;
  // SI value = number * scale / divisor. Sub-units divide so that "4 mm" gives exactly
  // the double nearest 0.004, as if the user had typed it in metres.
  double scale;
  double divisor;
};

std::span<const DimensionInfo> dimension_table();
std::span<const Unit> unit_table();

const DimensionInfo& dimension_info(Dimension dimension);
const Unit* find_unit(std::string_view symbol);  // nullptr when unknown

// What a field of this dimension expects: "a time (s, ms, min, ...)" or "a number".
std::string expected_text(Dimension dimension);

// All unit symbols of a dimension, SI first: "s, ms, us, min, h".
std::string unit_list(Dimension dimension);

// A value in SI with its SI symbol for messages: "-3 kg/m^3", "1.5".
std::string format_si(double value, Dimension dimension);

struct QuantityResult {
  std::optional<double> value;  // SI; empty on error
  std::string error;            // complete message naming `field`, empty on success
};

// Parses "number", "number unit" or "numberunit". The number is finite decimal notation
// (NaN and infinities are refused); the unit must belong to `dimension`. `field` is the
// quoted name used in messages, e.g. "'duration'".
QuantityResult parse_quantity(std::string_view text, Dimension dimension, std::string_view field);

}  // namespace phymul::io
