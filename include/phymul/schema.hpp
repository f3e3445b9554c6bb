// The scene schema, field by field, for programs that edit a Scene (the Python module): a
// field's unit, range and documentation as the parameter table declares them, and its value
// checked as a scene file's would be.
#pragma once

#include <string>
#include <string_view>

namespace phymul {

struct SceneField {
  std::string section;  // "material": the parameter table's section
  std::string name;     // "stiffness"
  std::string unit;     // its SI symbol ("N/m"); "" for plain numbers and non-quantities
  std::string range;    // "> 0", "[0, 1)"; "" when unbounded
  std::string doc;
};

// The field, or std::invalid_argument naming the unknown one (with a did-you-mean).
SceneField scene_field(std::string_view section, std::string_view name);

// value (SI) checked against the field's range: returned as is, or std::invalid_argument
// with the scene reader's message ("'stiffness' must be > 0 N/m (got -5 N/m)"). The field
// must be a number, a whole number, a vector or a schedule (its values are checked).
double check_scene_field(std::string_view section, std::string_view name, double value);

// "4 mm", "0.7 kN/m" or a bare number (SI) parsed in the field's unit and checked as above.
double parse_scene_field(std::string_view section, std::string_view name, std::string_view text);

}  // namespace phymul
