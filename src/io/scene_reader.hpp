// Table-driven reading of the YAML maps of a scene file: each map is checked against one
// section of the parameter table, and each value against its field's kind, unit and range.
// Problems are collected, never thrown, so that one run reports all of them.
#pragma once

#include <yaml-cpp/yaml.h>

#include <Eigen/Core>
#include <array>
#include <functional>
#include <initializer_list>
#include <map>
#include <optional>
#include <set>
#include <stdexcept>
#include <string>
#include <string_view>
#include <type_traits>
#include <utility>
#include <variant>
#include <vector>

#include "io/parameter_table.hpp"
#include "phymul/scene.hpp"
#include "phymul/scene_io.hpp"

namespace phymul::io {

// Collects the diagnostics of one scene file.
class SceneContext {
 public:
  explicit SceneContext(std::string file) : file_(std::move(file)) {}

  const std::string& file() const { return file_; }
  SourceLoc loc(const YAML::Mark& mark) const;  // 1-based; 0 for nodes without a mark
  SourceLoc loc(const YAML::Node& node) const { return loc(node.Mark()); }
  void error(SourceLoc loc, std::string message);
  // Sorted by position, so the report reads top to bottom.
  std::vector<Diagnostic> sorted_diagnostics() const;
  bool ok() const { return diagnostics_.empty(); }

 private:
  std::string file_;
  std::vector<Diagnostic> diagnostics_;
};

// "a list", "a map", "nothing" or the quoted scalar: what was found instead of a value.
std::string describe_node(const YAML::Node& node);

// A YAML map read against one section of the table. Construction reports unknown and
// repeated keys, missing required fields, fields that do not apply (see Parameter::when)
// and one-of groups. Each read() then checks one field: it returns true when `out` was
// set from the scene or from the table default, false when the field is absent without
// default, does not apply, or is invalid (then diagnosed).
class SectionReader {
 public:
  // `map` is a YAML map, or a null node for an omitted section; `where` names it in
  // messages ("'material'", "'objects[0]'", "the top level").
  SectionReader(SceneContext& context, const YAML::Node& map, std::string_view section,
                std::string where, SourceLoc loc);

  const SourceLoc& loc() const { return loc_; }
  const std::string& where() const { return where_; }
  SceneContext& context() const { return *context_; }
  // Position of the value the scene gives for `name`, if any.
  std::optional<SourceLoc> value_loc(std::string_view name) const;
  // Whether the scene gives `name` a valid value that read_fields read.
  bool given(std::string_view name) const { return given_.contains(name); }
  const std::string& section() const { return section_; }

  bool read(std::string_view name, double& out);
  bool read(std::string_view name, std::optional<double>& out);  // the keyword gives nullopt
  bool read(std::string_view name, Eigen::Vector3d& out);
  // A vector whose unit is set by the enclosing field (schedule values).
  bool read(std::string_view name, Eigen::Vector3d& out, Dimension dimension);
  bool read(std::string_view name, int& out);
  bool read(std::string_view name, long& out);
  bool read(std::string_view name, bool& out);
  bool read(std::string_view name, std::array<int, 3>& out);
  bool read(std::string_view name, std::vector<int>& out);     // integers
  bool read(std::string_view name, std::array<bool, 3>& out);  // axes
  bool read(std::string_view name, std::string& out);          // name or choice
  bool read(std::string_view name, NodeSelector& out);
  bool read(std::string_view name, Schedule& out);
  // A scalar schedule (scene_reader_interactions.cpp): values in x, each checked against the
  // field's range and in the field's unit.
  bool read_scalar(std::string_view name, Schedule& out);
  // A list of object names (scene_reader_interactions.cpp), with where each was written.
  bool read(std::string_view name, std::vector<std::string>& out, std::vector<SourceLoc>& locs);

  // A nested map: nullopt when it is invalid, or absent while it has required fields.
  std::optional<SectionReader> map(std::string_view name);
  // Calls `read_entry` for each map of a list field, in order.
  void items(std::string_view name, const std::function<void(SectionReader&)>& read_entry);

  // Throws std::logic_error when a field of the section was never read: the table and the
  // parser disagree. Deterministic per code path, so tests catch it.
  void done() const;

  // Reads every field of the section that lands in a member of Spec (Parameter::lands), each
  // into its member; an absent field leaves the member at Spec's default.
  template <class Spec>
  void read_fields(Spec& spec);

 private:
  enum class Applies { yes, no, unknown };
  struct Entry {
    YAML::Node key, value;
  };
  struct Value {  // a field's value: the scene's, or the parsed table default
    YAML::Node node;
    SourceLoc loc;
    const Parameter* parameter;
    bool from_default;
  };
  struct Event {  // one entry of a schedule
    double t;
    Eigen::Vector3d value;
    SourceLoc loc;  // of its time
  };

  void check_keys(const YAML::Node& map);
  void check_presence();
  void check_groups();
  void report_not_applicable(const Parameter& parameter, const Entry& given) const;
  std::string unknown_key_message(std::string_view key) const;
  Applies applies(const Parameter& parameter) const;
  std::optional<std::string> current_word(std::string_view key) const;
  const Parameter& parameter(std::string_view name, std::initializer_list<Kind> kinds);
  const Entry* entry(std::string_view name) const;
  std::optional<Value> lookup(std::string_view name, std::initializer_list<Kind> kinds);
  SourceLoc node_loc(const Value& value, const YAML::Node& node) const;
  void error(const SourceLoc& loc, std::string message) const;
  std::optional<std::string> scalar(const Value& value, std::string_view expected);
  bool check_range(const Parameter& parameter, const SourceLoc& loc, std::string_view label,
                   double value);
  std::optional<double> quantity(const Value& value, const YAML::Node& node, std::string_view label,
                                 Dimension dimension);
  std::optional<long> integer(const Value& value, const YAML::Node& node, std::string_view label);
  template <class Item, class ReadItem>
  std::optional<std::array<Item, 3>> triple(const Value& value, ReadItem read_item);
  std::optional<Eigen::Vector3d> vector(const Value& value, Dimension dimension);
  bool read_selector_text(const Value& value, const std::string& text, NodeSelector& out);
  bool read_index_token(const Value& value, std::string_view token, std::vector<int>& out);
  bool read_index_list(const Value& value, NodeSelector& out);
  bool read_shape(const Value& value, NodeSelector& out);
  bool read_box(SectionReader& box, NodeSelector& out);
  bool read_sphere(SectionReader& sphere, NodeSelector& out);
  bool read_half_space(SectionReader& half_space, NodeSelector& out);
  bool read_events(const Value& value, Schedule& out);
  bool read_scalar_events(const Value& value, Schedule& out);
  std::optional<Event> read_event(const Value& value, const YAML::Node& node,
                                  const std::string& label);

  SceneContext* context_;
  std::string section_;
  std::string where_;
  SourceLoc loc_;
  std::map<std::string, Entry, std::less<>> entries_;
  std::set<std::string, std::less<>> read_;
  std::set<std::string, std::less<>> given_;
};

namespace detail {

// One field into its member: a Schedule member may take a constant (`force`, `pressure`).
template <class Spec, class Member>
bool read_member(SectionReader& reader, const Parameter& p, Spec& spec, const Member& member) {
  if constexpr (std::is_same_v<Member, ChoiceMember<Spec>>) {
    std::string word;
    if (!reader.read(p.name, word)) return false;
    member.set(spec, word);
    return true;
  } else {
    auto& target = spec.*member;
    if constexpr (std::is_same_v<std::decay_t<decltype(target)>, Schedule>) {
      if (p.kind == Kind::scalar_schedule) return reader.read_scalar(p.name, target);
      if (p.kind == Kind::quantity) {
        double value = 0.0;
        if (!reader.read(p.name, value)) return false;
        target = Schedule::constant({value, 0.0, 0.0});
        return true;
      }
      if (p.kind == Kind::vector) {
        Eigen::Vector3d value = Eigen::Vector3d::Zero();
        if (!reader.read(p.name, value)) return false;
        target = Schedule::constant(value);
        return true;
      }
    }
    return reader.read(p.name, target);
  }
}

}  // namespace detail

template <class Spec>
void SectionReader::read_fields(Spec& spec) {
  for (const Parameter* p : section_parameters(section_)) {
    const auto* member = std::any_cast<FieldMember<Spec>>(&p->lands.member);
    if (!member) continue;
    const bool ok =
        std::visit([&](const auto& m) { return detail::read_member(*this, *p, spec, m); }, *member);
    if (ok && value_loc(p->name)) given_.emplace(p->name);
  }
}

}  // namespace phymul::io

namespace phymul {

// Scene text parsed and checked against the schema, and no more: no mesh file read, no
// calibration (parse_scene does both after it; the fuzzer stops here).
Scene read_scene_text(const std::string& text, const std::string& file_name);

}  // namespace phymul
