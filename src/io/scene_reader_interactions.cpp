#include <fmt/format.h>

#include <algorithm>

#include "io/scene_interactions.hpp"

namespace phymul::io {

namespace {

bool is_object_name(std::string_view text) {
  return !text.empty() && std::all_of(text.begin(), text.end(), [](char c) {
    return (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9') || c == '_' ||
           c == '-';
  });
}

// A unit direction from a vector field that must not be zero; false (diagnosed) otherwise.
bool read_direction(SceneContext& context, SectionReader& reader, std::string_view name,
                    Eigen::Vector3d& out) {
  Eigen::Vector3d v = out;
  if (!reader.read(name, v)) return false;
  if (v.cwiseAbs().maxCoeff() == 0.0) {
    context.error(
        reader.value_loc(name).value_or(reader.loc()),
        fmt::format("'{}' in {} must be a non-zero vector (got [0, 0, 0])", name, reader.where()));
    return false;
  }
  out = v.stableNormalized();
  return true;
}

}  // namespace

// ---- SectionReader members for the new kinds

bool SectionReader::read_scalar(std::string_view name, Schedule& out) {
  const auto value = lookup(name, {Kind::scalar_schedule});
  if (!value) return false;
  if (value->node.IsScalar()) {  // a constant: one event at t = 0
    const auto number =
        quantity(*value, value->node, fmt::format("'{}'", name), value->parameter->dimension);
    if (number) out = Schedule::constant(Eigen::Vector3d(*number, 0.0, 0.0));
    return number.has_value();
  }
  if (!value->node.IsSequence() || value->node.size() == 0) {
    error(
        value->loc,
        fmt::format("'{}' expects a quantity or a non-empty list of {{t, value}} events, got {}",
                    name, value->node.IsSequence() ? "an empty list" : describe_node(value->node)));
    return false;
  }
  return read_scalar_events(*value, out);
}

bool SectionReader::read_scalar_events(const Value& value, Schedule& out) {
  Schedule schedule;
  bool ok = true;
  size_t i = 0;
  for (auto it = value.node.begin(); it != value.node.end(); ++it, ++i) {
    const std::string label = fmt::format("'{}[{}]'", value.parameter->name, i);
    const YAML::Node node = *it;
    if (!node.IsMap()) {
      error(node_loc(value, node), fmt::format("{} expects a map {{t: ..., value: ...}}, got {}",
                                               label, describe_node(node)));
      ok = false;
      continue;
    }
    SectionReader event(*context_, node, "scalar_schedule", label, context_->loc(node));
    double t = 0.0;
    const bool has_t = event.read("t", t);
    // The value takes the unit and range of the scheduled field, not of `value` itself.
    bool has_value = false;
    double number = 0.0;
    if (const auto v = event.lookup("value", {Kind::quantity})) {
      const std::string what = fmt::format("{} value", label);
      const auto q = quantity(*v, v->node, what, value.parameter->dimension);
      if (q && check_range(*value.parameter, v->loc, what, *q)) {
        number = *q;
        has_value = true;
      }
    }
    event.done();
    const SourceLoc at = event.value_loc("t").value_or(event.loc());
    if (!has_t || !has_value) {
      ok = false;
      continue;
    }
    if (!schedule.times.empty() && t <= schedule.times.back()) {
      error(at, fmt::format("schedule times must be strictly increasing: {} has t = {} after "
                            "t = {}",
                            label, format_si(t, Dimension::time),
                            format_si(schedule.times.back(), Dimension::time)));
      ok = false;
      continue;
    }
    schedule.times.push_back(t);
    schedule.values.push_back(Eigen::Vector3d(number, 0.0, 0.0));
  }
  if (ok) out = std::move(schedule);
  return ok;
}

bool SectionReader::read(std::string_view name, std::vector<std::string>& out,
                         std::vector<SourceLoc>& locs) {
  const auto value = lookup(name, {Kind::names});
  if (!value) return false;
  const std::string quoted = fmt::format("'{}'", name);
  const Range& count = value->parameter->range;
  if (!value->node.IsSequence()) {
    error(value->loc, fmt::format("{} expects a list of object names such as [a, b], got {}",
                                  quoted, describe_node(value->node)));
    return false;
  }
  const double n = double(value->node.size());
  if ((count.min && n < *count.min) || (count.max && n > *count.max)) {
    const std::string wanted = count.min && count.max && *count.min == *count.max
                                   ? fmt::format("exactly {}", *count.min)
                                   : fmt::format("at least {}", count.min.value_or(0.0));
    const double shown = count.min.value_or(0.0);
    error(value->loc, fmt::format("{} needs {} object name{} (got {})", quoted, wanted,
                                  shown == 1 ? "" : "s", value->node.size()));
    return false;
  }
  std::vector<std::string> names;
  std::vector<SourceLoc> where;
  bool ok = true;
  for (auto it = value->node.begin(); it != value->node.end(); ++it) {
    const YAML::Node node = *it;
    const SourceLoc at = node_loc(*value, node);
    if (!node.IsScalar() || !is_object_name(node.Scalar())) {
      error(at, fmt::format("{} expects object names (letters, digits, '_' and '-'), got {}",
                            quoted, describe_node(node)));
      ok = false;
      continue;
    }
    if (std::find(names.begin(), names.end(), node.Scalar()) != names.end()) {
      error(at, fmt::format("{} names '{}' twice", quoted, node.Scalar()));
      ok = false;
      continue;
    }
    names.push_back(node.Scalar());
    where.push_back(at);
  }
  if (!ok) return false;
  out = std::move(names);
  locs = std::move(where);
  return true;
}

// ---- Sections

void read_pressure_cylinder(SectionReader& reader, PressureSpec& spec) {
  if (auto cylinder = reader.map("cylinder")) {
    cylinder->read_fields(spec);
    const bool has_axis = read_direction(reader.context(), *cylinder, "axis", spec.cylinder_axis);
    cylinder->done();
    spec.in_cylinder = cylinder->given("point") && has_axis && cylinder->given("radius");
  }
}

ObstacleSpec read_obstacle(SectionReader& reader, std::vector<ObjectReference>& references) {
  ObstacleSpec spec;
  spec.loc = reader.loc();
  reader.read_fields(spec);
  read_direction(reader.context(), reader, "axis", spec.axis);
  if (reader.read("objects", spec.objects, spec.object_locs))
    for (size_t i = 0; i < spec.objects.size(); ++i)
      references.push_back({spec.objects[i], spec.object_locs[i], reader.where()});
  reader.done();
  return spec;
}

ContactSpec read_contact(SectionReader& reader, std::vector<ObjectReference>& references) {
  ContactSpec spec;
  spec.loc = reader.loc();
  std::vector<std::string> names;
  std::vector<SourceLoc> locs;
  if (reader.read("objects", names, locs)) {
    for (size_t i = 0; i < 2; ++i) {
      spec.objects[i] = names[i];
      references.push_back({names[i], locs[i], reader.where()});
    }
  }
  reader.done();
  return spec;
}

namespace {

// An `object` field that names an object, checked against the objects once all are read.
void refer_object(SectionReader& reader, const std::string& object, SourceLoc& at,
                  std::vector<ObjectReference>& references) {
  if (!reader.given("object")) return;
  at = *reader.value_loc("object");
  references.push_back({object, at, reader.where()});
}

}  // namespace

NeedleSpec read_needle(SectionReader& reader, std::vector<ObjectReference>& references) {
  NeedleSpec spec;
  spec.loc = reader.loc();
  reader.read_fields(spec);
  read_direction(reader.context(), reader, "direction", spec.direction);
  reader.items("tissues", [&](SectionReader& r) {
    NeedleTissueSpec t;
    t.loc = r.loc();
    r.read_fields(t);
    refer_object(r, t.object, t.object_loc, references);
    r.done();
    spec.tissues.push_back(std::move(t));
  });
  if (auto r = reader.map("target"); r && reader.value_loc("target")) {
    NeedleTargetSpec t;
    t.loc = r->loc();
    r->read_fields(t);
    refer_object(*r, t.object, t.object_loc, references);
    r->done();
    spec.target = std::move(t);
  }
  reader.done();
  return spec;
}

}  // namespace phymul::io
