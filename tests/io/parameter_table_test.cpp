// The parameter table is data; these checks keep it self-consistent.
#include "io/parameter_table.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <map>
#include <set>

namespace phymul::io {
namespace {

bool has(const std::vector<std::string_view>& words, std::string_view word) {
  return std::find(words.begin(), words.end(), word) != words.end();
}

TEST(ParameterTableTest, FieldsAreUniqueAndBelongToKnownSections) {
  std::set<std::pair<std::string_view, std::string_view>> seen;
  for (const auto& p : parameter_table()) {
    EXPECT_TRUE(seen.insert({p.section, p.name}).second) << p.section << "." << p.name;
    EXPECT_NE(find_section(p.section), nullptr) << p.section;
    EXPECT_FALSE(p.doc.empty()) << p.name;
  }
  for (const auto& section : section_table())
    EXPECT_FALSE(section_parameters(section.name).empty()) << section.name;
}

TEST(ParameterTableTest, MapsAndListsNameTheirSectionAndNothingElseDoes) {
  for (const auto& p : parameter_table()) {
    const bool nested = p.kind == Kind::map || p.kind == Kind::list;
    EXPECT_EQ(nested, !p.child.empty()) << p.name;
    if (nested) {
      EXPECT_NE(find_section(p.child), nullptr) << p.child;
    }
  }
}

TEST(ParameterTableTest, ConditionsReferToChoicesOfTheSameSection) {
  for (const auto& p : parameter_table()) {
    for (const auto& condition : p.when) {
      const Parameter* key = find_parameter(p.section, condition.key);
      ASSERT_NE(key, nullptr) << p.name << " depends on " << condition.key;
      ASSERT_TRUE(key->kind == Kind::choice || key->kind == Kind::boolean) << condition.key;
      for (const auto value : condition.values) {
        const bool valid = key->kind == Kind::boolean ? value == "true" || value == "false"
                                                      : has(key->choices, value);
        EXPECT_TRUE(valid) << p.name << ": " << condition.key << " = " << value;
      }
    }
  }
}

TEST(ParameterTableTest, DefaultsRequiredAndGroupsDoNotContradict) {
  std::map<std::string, int> group_sizes;
  for (const auto& p : parameter_table()) {
    if (p.required) {
      EXPECT_TRUE(p.default_value.empty()) << p.name;
    }
    if (p.kind == Kind::choice) {
      EXPECT_FALSE(p.choices.empty()) << p.name;
      if (!p.default_value.empty()) {
        EXPECT_TRUE(has(p.choices, p.default_value)) << p.name;
      }
    } else {
      EXPECT_TRUE(p.choices.empty()) << p.name;
    }
    if (!p.keyword.empty()) {
      EXPECT_EQ(p.kind, Kind::quantity) << p.name;
    }
    if (!p.one_of.empty()) {
      EXPECT_FALSE(p.required) << p.name;
      EXPECT_TRUE(p.default_value.empty()) << p.name;
      ++group_sizes[std::string(p.section) + "/" + std::string(p.one_of)];
    }
  }
  for (const auto& [group, size] : group_sizes) EXPECT_GE(size, 2) << group;
}

TEST(ParameterTableTest, RangesAreWellFormed) {
  for (const auto& p : parameter_table()) {
    if (p.range.min && p.range.max) {
      EXPECT_LE(*p.range.min, *p.range.max) << p.name;
    }
    const bool numeric = p.kind == Kind::quantity || p.kind == Kind::vector ||
                         p.kind == Kind::integer || p.kind == Kind::integer_vector ||
                         p.kind == Kind::list || p.kind == Kind::names ||
                         p.kind == Kind::scalar_schedule || p.kind == Kind::integers;
    if (!numeric) {
      EXPECT_TRUE(p.range.unbounded()) << p.name;
    }
  }
}

TEST(ParameterTableTest, RangeTextAndViolations) {
  const Range open_closed{0.0, 1.0, true, false};
  EXPECT_EQ(open_closed.str(), "(0, 1]");
  EXPECT_EQ(open_closed.violation(0.0, Dimension::none), "> 0");
  EXPECT_EQ(open_closed.violation(1.0, Dimension::none), "");
  EXPECT_EQ(open_closed.violation(1.5, Dimension::none), "<= 1");
  const Range positive{0.0, std::nullopt, true, false};
  EXPECT_EQ(positive.str(), "> 0");
  EXPECT_EQ(positive.violation(-3.0, Dimension::density), "> 0 kg/m^3");
  EXPECT_EQ((Range{1.0, 1000.0}).str(), "[1, 1000]");
  EXPECT_EQ((Range{0.0, std::nullopt}).str(), ">= 0");
}

TEST(ParameterTableTest, EditDistanceCountsTranspositionsOnce) {
  EXPECT_EQ(edit_distance("duration", "duration"), 0);
  EXPECT_EQ(edit_distance("duraton", "duration"), 1);
  EXPECT_EQ(edit_distance("duartion", "duration"), 1);
  EXPECT_EQ(edit_distance("", "abc"), 3);
  EXPECT_EQ(edit_distance("kitten", "sitting"), 3);
}

TEST(ParameterTableTest, SuggestsOnlyCloseMatches) {
  const std::vector<std::string_view> keys{"dt", "dt_safety", "duration", "damping"};
  EXPECT_EQ(closest_match("duraton", keys), "duration");
  EXPECT_EQ(closest_match("Duration", keys), "duration");
  EXPECT_EQ(closest_match("dampnig", keys), "damping");
  EXPECT_EQ(closest_match("d", keys), "dt");
  EXPECT_FALSE(closest_match("colour", keys).has_value());
  EXPECT_FALSE(closest_match("xyz", keys).has_value());
}

}  // namespace
}  // namespace phymul::io
