#include "io/units.hpp"

#include <gtest/gtest.h>

#include <numbers>
#include <set>
#include <string>

namespace phymul::io {
namespace {

double si(std::string_view text, Dimension dimension) {
  const auto result = parse_quantity(text, dimension, "'field'");
  EXPECT_TRUE(result.value.has_value()) << text << ": " << result.error;
  return result.value.value_or(-12345.0);
}

std::string error(std::string_view text, Dimension dimension) {
  const auto result = parse_quantity(text, dimension, "'field'");
  EXPECT_FALSE(result.value.has_value()) << text << " gave " << result.value.value_or(0.0);
  return result.error;
}

TEST(UnitsTest, NumbersWithoutUnitAreSi) {
  EXPECT_EQ(si("9.81", Dimension::acceleration), 9.81);
  EXPECT_EQ(si("-2.5e-3", Dimension::length), -0.0025);
  EXPECT_EQ(si("+3", Dimension::time), 3.0);
  EXPECT_EQ(si(".5", Dimension::none), 0.5);
  EXPECT_EQ(si("5.", Dimension::none), 5.0);
  EXPECT_EQ(si("  7  ", Dimension::none), 7.0);
}

TEST(UnitsTest, ConvertsTheRequiredExamples) {
  EXPECT_DOUBLE_EQ(si("4 mm", Dimension::length), 0.004);
  EXPECT_DOUBLE_EQ(si("15.3 kPa", Dimension::pressure), 15300.0);
  EXPECT_DOUBLE_EQ(si("1 g/cm^3", Dimension::density), 1000.0);
  EXPECT_DOUBLE_EQ(si("2mN", Dimension::force), 0.002);
}

TEST(UnitsTest, SubUnitsGiveTheSameDoubleAsTypingSi) {
  // Dividing by 1000 rather than multiplying by 0.001 keeps "4 mm" == 0.004 bit for bit.
  EXPECT_EQ(si("4 mm", Dimension::length), 0.004);
  EXPECT_EQ(si("1.5 cm", Dimension::length), 0.015);
  EXPECT_EQ(si("2mN", Dimension::force), 0.002);
  EXPECT_EQ(si("3 ms", Dimension::time), 0.003);
  EXPECT_EQ(si("250 g", Dimension::mass), 0.25);
}

TEST(UnitsTest, ConvertsEveryDimension) {
  EXPECT_DOUBLE_EQ(si("2 um", Dimension::length), 2e-6);
  EXPECT_DOUBLE_EQ(si("2 min", Dimension::time), 120.0);
  EXPECT_DOUBLE_EQ(si("1.5 h", Dimension::time), 5400.0);
  EXPECT_DOUBLE_EQ(si("20 us", Dimension::time), 2e-5);
  EXPECT_DOUBLE_EQ(si("5 mg", Dimension::mass), 5e-6);
  EXPECT_DOUBLE_EQ(si("1.2 kN", Dimension::force), 1200.0);
  EXPECT_DOUBLE_EQ(si("50 N/m", Dimension::stiffness), 50.0);
  EXPECT_DOUBLE_EQ(si("0.5 N/mm", Dimension::stiffness), 500.0);
  EXPECT_DOUBLE_EQ(si("2 kN/m", Dimension::stiffness), 2000.0);
  EXPECT_DOUBLE_EQ(si("3 MPa", Dimension::pressure), 3e6);
  EXPECT_DOUBLE_EQ(si("10 mmHg", Dimension::pressure), 1333.22387415);
  EXPECT_DOUBLE_EQ(si("10 cmH2O", Dimension::pressure), 980.665);
  EXPECT_DOUBLE_EQ(si("1.05 g/mL", Dimension::density), 1050.0);
  EXPECT_DOUBLE_EQ(si("1000 kg/m^3", Dimension::density), 1000.0);
  EXPECT_DOUBLE_EQ(si("-1 g0", Dimension::acceleration), -9.80665);
  EXPECT_DOUBLE_EQ(si("-9.81 m/s^2", Dimension::acceleration), -9.81);
  EXPECT_DOUBLE_EQ(si("5 1/s", Dimension::rate), 5.0);
  EXPECT_DOUBLE_EQ(si("90 deg", Dimension::angle), std::numbers::pi / 2);
  EXPECT_DOUBLE_EQ(si("-180deg", Dimension::angle), -std::numbers::pi);
  EXPECT_DOUBLE_EQ(si("0.5 rad", Dimension::angle), 0.5);
  EXPECT_DOUBLE_EQ(si("5 Hz", Dimension::rate), 5.0);
  EXPECT_DOUBLE_EQ(si("2 L", Dimension::volume), 2e-3);
  EXPECT_DOUBLE_EQ(si("3 mL", Dimension::volume), 3e-6);
  EXPECT_DOUBLE_EQ(si("3 cm^3", Dimension::volume), 3e-6);
  EXPECT_DOUBLE_EQ(si("1 m^3", Dimension::volume), 1.0);
}

TEST(UnitsTest, WrongDimensionNamesFieldUnitAndExpectedDimension) {
  const auto result = parse_quantity("2 mm", Dimension::time, "'duration'");
  EXPECT_EQ(result.error, "'duration' expects a time (s, ms, min, ...), got 'mm'");
  EXPECT_EQ(error("1 kg", Dimension::force), "'field' expects a force (N, mN, kN, ...), got 'kg'");
}

TEST(UnitsTest, UnknownUnitListsTheUnitsOfTheDimension) {
  EXPECT_EQ(error("3 furlongs", Dimension::length),
            "'field' has an unknown unit 'furlongs' (length units: m, cm, mm, um, \u00b5m)");
  EXPECT_EQ(error("4 MM", Dimension::length),
            "'field' has an unknown unit 'MM' (length units: m, cm, mm, um, \u00b5m)");
}

TEST(UnitsTest, PlainNumbersRefuseUnits) {
  EXPECT_EQ(error("0.5 s", Dimension::none),
            "'field' takes a plain number without a unit, got 's'");
}

TEST(UnitsTest, RejectsNanAndInfinityInEverySpelling) {
  for (const char* text : {"nan", "NaN", ".nan", ".NaN", ".NAN", "-nan", "inf", "-inf", "+inf",
                           ".inf", "-.inf", ".Inf", "Infinity", "nan mm", "inf N"})
    EXPECT_EQ(error(text, Dimension::length),
              std::string("'field' must be a finite number (got '") + text + "')");
}

TEST(UnitsTest, RejectsOverflow) {
  EXPECT_EQ(error("1e999", Dimension::none),
            "'field' is out of the representable range (got '1e999')");
  EXPECT_EQ(error("1e308 kN", Dimension::force),
            "'field' is out of the representable range (got '1e308 kN')");
}

TEST(UnitsTest, RejectsTextThatIsNotANumber) {
  EXPECT_EQ(error("", Dimension::length), "'field' expects a length (m, cm, mm, ...), got nothing");
  EXPECT_EQ(error("abc", Dimension::none), "'field' expects a number, got 'abc'");
  EXPECT_EQ(error("mm", Dimension::length), "'field' expects a length (m, cm, mm, ...), got 'mm'");
  EXPECT_EQ(error("-", Dimension::none), "'field' expects a number, got '-'");
  EXPECT_FALSE(parse_quantity("0x10", Dimension::none, "'f'").value);
  EXPECT_FALSE(parse_quantity("4 mm mm", Dimension::length, "'f'").value);
  EXPECT_FALSE(parse_quantity("1,5", Dimension::none, "'f'").value);
}

TEST(UnitsTest, UnitTableIsConsistent) {
  std::set<std::string_view> symbols;
  for (const auto& unit : unit_table()) {
    EXPECT_TRUE(symbols.insert(unit.symbol).second) << "duplicate " << unit.symbol;
    EXPECT_EQ(find_unit(unit.symbol), &unit);
    EXPECT_NE(unit.dimension, Dimension::none) << unit.symbol;
    EXPECT_GT(unit.scale, 0.0);
    EXPECT_GT(unit.divisor, 0.0);
  }
  for (const auto& info : dimension_table()) {
    if (info.dimension == Dimension::none) continue;
    // The SI unit of each dimension converts with factor 1 and comes first in its list.
    const Unit* unit = find_unit(info.si);
    ASSERT_NE(unit, nullptr) << info.name;
    EXPECT_EQ(unit->scale / unit->divisor, 1.0);
    EXPECT_EQ(unit_list(info.dimension).rfind(std::string(info.si), 0), 0u);
  }
}

TEST(UnitsTest, FormatsSiValuesWithTheirSymbol) {
  EXPECT_EQ(format_si(-3.0, Dimension::density), "-3 kg/m^3");
  EXPECT_EQ(format_si(0.004, Dimension::length), "0.004 m");
  EXPECT_EQ(format_si(1.5, Dimension::none), "1.5");
}

}  // namespace
}  // namespace phymul::io
