// The scene parameter table: every section and field of a scene file, as data. The reader
// validates against it, its messages quote it and scene_reference_markdown() prints it, so a
// field documented is a field checked.
#pragma once

#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "io/field_landing.hpp"
#include "io/units.hpp"
#include "model/closest_match.hpp"

namespace phymul::io {

enum class Kind {
  quantity,         // number with an optional unit of `dimension`
  vector,           // [x, y, z] of quantities, each with its own optional unit
  integer,          // whole number
  integer_vector,   // [x, y, z] of whole numbers
  integers,         // list of whole numbers (range: of each value)
  boolean,          // true | false
  choice,           // one of `choices`
  name,             // [A-Za-z0-9_-]+
  axes,             // non-empty combination of x, y, z
  selector,         // node selector: name, index list or {box|sphere|half_space: ...}
  schedule,         // list of {t, value} events
  scalar_schedule,  // list of {t, value} events with a single quantity each (range: of values)
  names,            // list of object names (range: of the entry count)
  list,             // list of maps, each described by section `child`
  map,              // map described by section `child`
  path,             // a file path, relative to the scene file's directory
  text,             // any non-empty text (a component name of a file, spaces allowed)
};

// Allowed interval, applied to each component of vectors and to the entry count of lists.
struct Range {
  std::optional<double> min, max;
  bool min_open = false, max_open = false;

  bool unbounded() const { return !min && !max; }
  // The violated bound as a message fragment ("> 0 kg/m^3"), or "" when `value` is inside.
  std::string violation(double value, Dimension dimension) const;
  std::string str() const;  // "(0, 1]", ">= 1", "[1, 1000]"
};

// The field exists only when the sibling field `key` holds one of `values`.
struct Condition {
  std::string_view key;
  std::vector<std::string_view> values;
};

struct Parameter {
  std::string_view section;
  std::string_view name;
  Kind kind;
  Dimension dimension = Dimension::none;
  Range range{};
  std::vector<std::string_view> choices{};
  // YAML text used when the key is absent; "" = none. A field that `lands` in a Spec takes
  // its Spec's default (the table fills it in); only fields read by hand give it here.
  std::string default_value{};
  std::string_view default_note{};  // reference text when absence means something else
  bool required = false;
  std::string_view keyword{};     // a word accepted instead of a value ("auto")
  std::vector<Condition> when{};  // all must hold for the field to exist
  std::string_view one_of{};      // group name: exactly one field of the group is given
  std::string_view child{};       // map and list: the section of the content
  bool uniform = false;           // vector: a single value stands for [v, v, v]
  std::string_view doc{};
  Landing lands{};       // where the value lands in the Scene (read_fields); empty: by hand
  bool editable = true;  // SceneField::editable: false when only a scene file sets it
};

struct Section {
  std::string_view name;  // as used in Parameter::section
  std::string_view path;  // where it sits in a scene file, for the reference
  std::string_view doc;
};

std::span<const Section> section_table();
std::span<const Parameter> parameter_table();

const Section* find_section(std::string_view name);
const Parameter* find_parameter(std::string_view section, std::string_view name);
std::vector<const Parameter*> section_parameters(std::string_view section);

std::string_view kind_name(Kind kind);  // the reference's wording: "3 integers"
std::string_view kind_word(Kind kind);  // a program's: "integer_vector" (SceneField::kind)

// The fields of `needles` (parameter_table_needles.cpp), part of parameter_table().
std::vector<Parameter> needle_parameters();

}  // namespace phymul::io
