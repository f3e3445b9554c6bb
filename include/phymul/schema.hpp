// The scene schema, field by field, for programs that edit a Scene (the Python module): a
// field's unit, range and documentation as the parameter table declares them, where its value
// lands in the Scene, and its value checked as a scene file's would be.
#pragma once

#include <array>
#include <functional>
#include <optional>
#include <string>
#include <string_view>
#include <variant>
#include <vector>

#include "phymul/scene.hpp"

namespace phymul {

struct SceneField {
  std::string section;  // "material": the parameter table's section
  std::string name;     // "stiffness"
  std::string kind;     // "quantity", "vector", "integer", "boolean", "choice", "schedule", ...
  std::string unit;     // its SI symbol ("N/m"); "" for plain numbers and non-quantities
  std::string range;    // "> 0", "[0, 1)"; "" when unbounded
  std::vector<std::string> choices;  // a choice's words
  std::string doc;
  // False when only a scene file sets it: it shaped what loading prepared (the mesh read, the
  // object's kind), so a program editing a loaded Scene may read it but not change it.
  bool editable = true;
};

// A field whose value is a word (an enum, or an axis index), seen through its words.
template <class Spec>
struct ChoiceMember {
  std::function<std::string_view(const Spec&)> get;
  std::function<void(Spec&, std::string_view)> set;  // `word` is one of `words`
  std::vector<std::string_view> words;
};

// Where a field's value lands in the Spec its section fills.
template <class Spec>
using FieldMember =
    std::variant<double Spec::*, std::optional<double> Spec::*, int Spec::*, long Spec::*,
                 bool Spec::*, Eigen::Vector3d Spec::*, std::array<int, 3> Spec::*,
                 std::array<bool, 3> Spec::*, std::vector<int> Spec::*, std::string Spec::*,
                 Schedule Spec::*, NodeSelector Spec::*, ChoiceMember<Spec>>;

template <class Spec>
struct BoundField {
  SceneField field;
  FieldMember<Spec> member;
};

// The fields of the table that land in a Spec, in the table's order: SimulationSpec, ObjectSpec,
// MeshSpec, MeshTransform, MaterialSpec, LoadSpec, PressureSpec, ConstraintSpec, ObstacleSpec,
// OutputSpec, LinkSpec, MotionSpec, FibreSpec, NeedleSpec, NeedleTissueSpec, NeedleTargetSpec.
template <class Spec>
std::vector<BoundField<Spec>> bound_fields();

// The field, or std::invalid_argument naming the unknown one (with a did-you-mean).
SceneField scene_field(std::string_view section, std::string_view name);

// value (SI) checked against the field's range: returned as is, or std::invalid_argument
// with the scene reader's message ("'stiffness' must be > 0 N/m (got -5 N/m)"). The field
// must be a number, a whole number, a vector or a schedule (its values are checked).
double check_scene_field(std::string_view section, std::string_view name, double value);

// "4 mm", "0.7 kN/m" or a bare number (SI) parsed in the field's unit and checked as above.
double parse_scene_field(std::string_view section, std::string_view name, std::string_view text);

}  // namespace phymul
