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

}  // namespace

SceneField scene_field(std::string_view section, std::string_view name) {
  const io::Parameter& p = find(section, name);
  return {std::string(p.section), std::string(p.name),
          std::string(io::dimension_info(p.dimension).si), p.range.str(), std::string(p.doc)};
}

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
