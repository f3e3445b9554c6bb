// The scene reference, printed from the parameter table so that it cannot drift from what
// the reader accepts.
#include <fmt/format.h>

#include <string>

#include "io/parameter_table.hpp"
#include "io/units.hpp"
#include "phymul/scene.hpp"
#include "phymul/scene_io.hpp"

namespace phymul {

namespace {

using io::Kind;
using io::Parameter;

// Table cells must not contain a bare '|'.
std::string cell(std::string_view text) {
  std::string out;
  for (const char c : text) {
    if (c == '|') out += '\\';
    out += c;
  }
  return out.empty() ? "—" : out;
}

std::string code_list(const std::vector<std::string_view>& words, std::string_view separator) {
  std::string out;
  for (const auto word : words) out += fmt::format("{}`{}`", out.empty() ? "" : separator, word);
  return out;
}

std::string type_text(const Parameter& p) {
  // A quantity without dimension is what users call a number.
  const bool plain = p.kind == Kind::quantity && p.dimension == io::Dimension::none;
  std::string kind = plain ? "number" : std::string(io::kind_name(p.kind));
  if (p.uniform) kind += " or number";
  return p.keyword.empty() ? kind : fmt::format("{} or `{}`", kind, p.keyword);
}

std::string unit_text(const Parameter& p) {
  return std::string(io::dimension_info(p.dimension).si);
}

std::string range_text(const Parameter& p) {
  if (p.kind == Kind::choice) return code_list(p.choices, ", ");
  if (p.range.unbounded()) return {};
  const std::string range = p.range.str();
  if (p.kind == Kind::names && p.range.min && p.range.max && *p.range.min == *p.range.max)
    return fmt::format("exactly {} entries", *p.range.min);
  if (p.kind == Kind::names)
    return fmt::format("at least {} entr{}", *p.range.min, *p.range.min == 1 ? "y" : "ies");
  if (p.kind == Kind::scalar_schedule) return "each value " + range;
  if (p.kind == Kind::list)
    return fmt::format("at least {} entr{}", *p.range.min, *p.range.min == 1 ? "y" : "ies");
  if (p.kind == Kind::vector || p.kind == Kind::integer_vector || p.kind == Kind::integers)
    return "each " + range;
  return range;
}

std::string default_text(const Parameter& p) {
  if (p.required) return "**required**";
  if (!p.default_value.empty()) return fmt::format("`{}`", p.default_value);
  if (!p.one_of.empty()) {
    std::vector<std::string_view> group;
    for (const auto* member : io::section_parameters(p.section))
      if (member->one_of == p.one_of) group.push_back(member->name);
    return "one of " + code_list(group, ", ");
  }
  return std::string(p.default_note);
}

std::string description_text(const Parameter& p) {
  std::string out(p.doc);
  for (const auto& condition : p.when) {
    std::vector<std::string_view> values(condition.values.begin(), condition.values.end());
    out += fmt::format(" Only when `{}` is {}.", condition.key, code_list(values, " or "));
  }
  if (!p.child.empty() && p.kind == Kind::list)
    out += fmt::format(" Entries: see `{}`.", io::find_section(p.child)->path);
  else if (!p.child.empty())
    out += fmt::format(" See `{}`.", io::find_section(p.child)->path);
  return out;
}

std::string heading(const io::Section& section) {
  return section.name == "scene" ? std::string("Top level") : fmt::format("`{}`", section.path);
}

std::string section_markdown(const io::Section& section) {
  std::string out = fmt::format("## {}\n\n{}\n\n", heading(section), section.doc);
  out += "| field | type | unit | range | default | description |\n";
  out += "|---|---|---|---|---|---|\n";
  for (const auto* p : io::section_parameters(section.name))
    out += fmt::format("| `{}` | {} | {} | {} | {} | {} |\n", p->name, cell(type_text(*p)),
                       cell(unit_text(*p)), cell(range_text(*p)), cell(default_text(*p)),
                       cell(description_text(*p)));
  return out + "\n";
}

std::string units_markdown() {
  std::string out =
      "## Quantities and units\n\n"
      "A quantity is a number, taken in SI units, or a string `number unit` such as `4 mm` "
      "(the space is optional: `4mm`). A vector is a list of exactly 3 quantities, each with "
      "its own optional unit: `[0, 0, -9.81 m/s^2]`. NaN and infinities are refused. "
      "Integers must be whole numbers; booleans are `true` or `false`.\n\n"
      "| dimension | SI unit | accepted units |\n|---|---|---|\n";
  for (const auto& info : io::dimension_table()) {
    if (info.dimension == io::Dimension::none) continue;
    out += fmt::format("| {} | `{}` | {} |\n", info.name, info.si,
                       cell(io::unit_list(info.dimension)));
  }
  return out + "\n";
}

}  // namespace

std::string scene_reference_markdown() {
  std::string out =
      "# Scene file reference\n\n"
      "A scene is a YAML map. Every problem found in a scene is reported with its file, line "
      "and column; unknown keys get a suggestion.\n\n";
  out += units_markdown();
  for (const auto& section : io::section_table()) out += section_markdown(section);
  return out;
}

}  // namespace phymul
