// Field-level access to the parameter table (schema.hpp).
#include "phymul/schema.hpp"

#include <fmt/format.h>

#include <cmath>
#include <stdexcept>
#include <vector>

#include "io/parameter_table.hpp"
#include "io/units.hpp"

namespace phymul {
namespace {

const io::Parameter& find(std::string_view section, std::string_view name) {
  if (const io::Parameter* p = io::find_parameter(section, name)) return *p;
  std::vector<std::string_view> known;
  for (const io::Parameter* p : io::section_parameters(section)) known.push_back(p->name);
  if (known.empty())
    throw std::invalid_argument(fmt::format("the scene schema has no section '{}'", section));
  std::string hint;
  if (const auto suggestion = closest_match(name, known))
    hint = fmt::format(" (did you mean '{}'?)", *suggestion);
  throw std::invalid_argument(fmt::format("'{}' has no field '{}'{}", section, name, hint));
}

const io::Parameter& quantity(std::string_view section, std::string_view name) {
  const io::Parameter& p = find(section, name);
  if (p.kind != io::Kind::quantity && p.kind != io::Kind::vector && p.kind != io::Kind::integer &&
      p.kind != io::Kind::schedule && p.kind != io::Kind::scalar_schedule)
    throw std::invalid_argument(fmt::format("'{}' in '{}' is not a quantity", name, section));
  return p;
}

SceneField field_of(const io::Parameter& p) {
  SceneField f;
  f.section = p.section;
  f.name = p.name;
  f.kind = io::kind_word(p.kind);
  f.unit = io::dimension_info(p.dimension).si;
  f.range = p.range.str();
  for (const auto word : p.choices) f.choices.emplace_back(word);
  f.doc = p.doc;
  f.editable = p.editable;
  return f;
}

}  // namespace

SceneField scene_field(std::string_view section, std::string_view name) {
  return field_of(find(section, name));
}

template <class Spec>
std::vector<BoundField<Spec>> bound_fields() {
  std::vector<BoundField<Spec>> out;
  for (const io::Parameter& p : io::parameter_table())
    if (const auto* member = std::any_cast<FieldMember<Spec>>(&p.lands.member))
      out.push_back({field_of(p), *member});
  return out;
}

template std::vector<BoundField<SimulationSpec>> bound_fields();
template std::vector<BoundField<ObjectSpec>> bound_fields();
template std::vector<BoundField<MeshSpec>> bound_fields();
template std::vector<BoundField<MeshTransform>> bound_fields();
template std::vector<BoundField<MaterialSpec>> bound_fields();
template std::vector<BoundField<LoadSpec>> bound_fields();
template std::vector<BoundField<PressureSpec>> bound_fields();
template std::vector<BoundField<ConstraintSpec>> bound_fields();
template std::vector<BoundField<ObstacleSpec>> bound_fields();
template std::vector<BoundField<OutputSpec>> bound_fields();
template std::vector<BoundField<LinkSpec>> bound_fields();
template std::vector<BoundField<MotionSpec>> bound_fields();
template std::vector<BoundField<FibreSpec>> bound_fields();
template std::vector<BoundField<NeedleSpec>> bound_fields();
template std::vector<BoundField<NeedleTissueSpec>> bound_fields();
template std::vector<BoundField<NeedleTargetSpec>> bound_fields();

double check_scene_field(std::string_view section, std::string_view name, double value) {
  const io::Parameter& p = quantity(section, name);
  const std::string label = fmt::format("'{}'", name);
  if (!std::isfinite(value))
    throw std::invalid_argument(fmt::format("{} must be a finite number (got {})", label, value));
  const std::string violated = p.range.violation(value, p.dimension);
  if (!violated.empty())
    throw std::invalid_argument(
        fmt::format("{} must be {} (got {})", label, violated, io::format_si(value, p.dimension)));
  return value;
}

double parse_scene_field(std::string_view section, std::string_view name, std::string_view text) {
  const io::Parameter& p = quantity(section, name);
  const auto parsed = io::parse_quantity(text, p.dimension, fmt::format("'{}'", name));
  if (!parsed.value) throw std::invalid_argument(parsed.error);
  return check_scene_field(section, name, *parsed.value);
}

}  // namespace phymul
