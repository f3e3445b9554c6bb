#include "io/scene_reader.hpp"

#include <fmt/format.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <charconv>
#include <climits>
#include <cmath>

namespace phymul::io {

namespace {

constexpr std::array<std::string_view, 3> kAxes{"x", "y", "z"};
// Node indices are ints; a range selecting more than this is a typo, and expanding it
// would exhaust memory before the mesh could say so.
constexpr long long kMaxSelectedIndices = 10'000'000;
// Beyond 2^53 a double no longer holds every whole number.
constexpr double kMaxExactInteger = 9007199254740992.0;
constexpr std::string_view kSelectorForms =
    "a node-set name, an index list such as \"0-3,7\", a list of indices, or a map with "
    "box, sphere or half_space";

std::string in_quotes(std::string_view name) { return fmt::format("'{}'", name); }

std::string join(const std::vector<std::string_view>& words, std::string_view separator) {
  std::string out;
  for (const auto word : words) {
    if (!out.empty()) out += separator;
    out += word;
  }
  return out;
}

// "'a' or 'b'", "'a', 'b' or 'c'"
std::string alternatives(const std::vector<std::string_view>& names) {
  std::string out;
  for (size_t i = 0; i < names.size(); ++i) {
    if (i > 0) out += i + 1 == names.size() ? " or " : ", ";
    out += in_quotes(names[i]);
  }
  return out;
}

bool is_name(std::string_view text) {
  return !text.empty() && std::all_of(text.begin(), text.end(), [](char c) {
    return (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9') || c == '_' ||
           c == '-';
  });
}

std::string_view trim(std::string_view s) {
  const auto first = s.find_first_not_of(" \t");
  if (first == std::string_view::npos) return {};
  return s.substr(first, s.find_last_not_of(" \t") - first + 1);
}

bool all_digits(std::string_view s) {
  return !s.empty() && std::all_of(s.begin(), s.end(), [](char c) { return c >= '0' && c <= '9'; });
}

// Digits as an index; nullopt beyond int.
std::optional<int> index_value(std::string_view digits) {
  long long value = 0;
  const auto [ptr, ec] = std::from_chars(digits.data(), digits.data() + digits.size(), value);
  if (ec != std::errc{} || ptr != digits.data() + digits.size() || value > INT_MAX)
    return std::nullopt;
  return int(value);
}

// An index list is made of digits, '-' and ','; anything else is a node-set name.
bool looks_like_index_list(std::string_view text) {
  const bool has_digit =
      std::any_of(text.begin(), text.end(), [](char c) { return c >= '0' && c <= '9'; });
  const bool only_list_chars = text.find_first_not_of("0123456789-, \t") == std::string_view::npos;
  return has_digit && only_list_chars;
}

bool contains(const std::vector<std::string_view>& words, std::string_view word) {
  return std::find(words.begin(), words.end(), word) != words.end();
}

bool has_required_fields(std::string_view section) {
  const auto fields = section_parameters(section);
  return std::any_of(fields.begin(), fields.end(),
                     [](const Parameter* p) { return p->required || !p->one_of.empty(); });
}

}  // namespace

// ---- SceneContext

SourceLoc SceneContext::loc(const YAML::Mark& mark) const {
  if (mark.is_null() || mark.line < 0 || mark.column < 0) return {file_, 0, 0};
  return {file_, mark.line + 1, mark.column + 1};
}

void SceneContext::error(SourceLoc loc, std::string message) {
  diagnostics_.push_back({std::move(loc), std::move(message)});
}

std::vector<Diagnostic> SceneContext::sorted_diagnostics() const {
  auto sorted = diagnostics_;
  const auto key = [](const Diagnostic& d) {
    return std::pair(d.loc.line == 0 ? INT_MAX : d.loc.line, d.loc.column);
  };
  std::stable_sort(sorted.begin(), sorted.end(),
                   [&](const Diagnostic& a, const Diagnostic& b) { return key(a) < key(b); });
  return sorted;
}

std::string describe_node(const YAML::Node& node) {
  switch (node.Type()) {
    case YAML::NodeType::Null:
      return "nothing";
    case YAML::NodeType::Sequence:
      return "a list";
    case YAML::NodeType::Map:
      return "a map";
    case YAML::NodeType::Scalar: {
      std::string text = node.Scalar();
      if (text.size() > 40) {
        size_t cut = 37;
        while (cut > 0 && (static_cast<unsigned char>(text[cut]) & 0xC0) == 0x80) --cut;
        text = text.substr(0, cut) + "...";  // cut on a UTF-8 character boundary
      }
      return in_quotes(text);
    }
    case YAML::NodeType::Undefined:
      break;
  }
  return "an undefined value";
}

// ---- SectionReader: construction checks the keys of the map as a whole

SectionReader::SectionReader(SceneContext& context, const YAML::Node& map, std::string_view section,
                             std::string where, SourceLoc loc)
    : context_(&context), section_(section), where_(std::move(where)), loc_(std::move(loc)) {
  if (find_section(section) == nullptr)
    throw std::logic_error(fmt::format("section '{}' is not in the parameter table", section));
  if (map.IsMap()) check_keys(map);
  check_presence();
  check_groups();
}

void SectionReader::error(const SourceLoc& loc, std::string message) const {
  context_->error(loc, std::move(message));
}

void SectionReader::check_keys(const YAML::Node& map) {
  for (auto it = map.begin(); it != map.end(); ++it) {
    const YAML::Node key = it->first;
    const SourceLoc at = context_->loc(key);
    if (!key.IsScalar()) {
      error(at, fmt::format("keys in {} must be plain names (got {})", where_, describe_node(key)));
      continue;
    }
    const std::string& name = key.Scalar();
    if (const auto first = entries_.find(name); first != entries_.end()) {
      error(at, fmt::format("{} is given twice in {} (first at line {})", in_quotes(name), where_,
                            context_->loc(first->second.key).line));
      continue;
    }
    if (find_parameter(section_, name) == nullptr) {
      error(at, unknown_key_message(name));
      continue;
    }
    entries_.emplace(name, Entry{key, it->second});
  }
}

std::string SectionReader::unknown_key_message(std::string_view key) const {
  std::vector<std::string_view> allowed;
  for (const Parameter* p : section_parameters(section_)) allowed.push_back(p->name);
  if (const auto suggestion = closest_match(key, allowed))
    return fmt::format("unknown key '{}' in {} (did you mean '{}'?)", key, where_, *suggestion);
  // A key put in the wrong section is a common slip; say where it belongs.
  std::vector<std::string_view> homes;
  for (const auto& parameter : parameter_table())
    if (parameter.name == key && !contains(homes, find_section(parameter.section)->path))
      homes.push_back(find_section(parameter.section)->path);
  if (!homes.empty())
    return fmt::format("unknown key '{}' in {} (it belongs in {}; allowed here: {})", key, where_,
                       join(homes, ", "), join(allowed, ", "));
  return fmt::format("unknown key '{}' in {} (allowed: {})", key, where_, join(allowed, ", "));
}

// The word a discriminating field holds (generator, type, surface), or nullopt when it is
// invalid: the fields depending on it are then neither required nor refused.
std::optional<std::string> SectionReader::current_word(std::string_view key) const {
  const Parameter* discriminator = find_parameter(section_, key);
  if (discriminator == nullptr)
    throw std::logic_error(fmt::format("condition on unknown field '{}' in '{}'", key, section_));
  const Entry* given = entry(key);
  if (given == nullptr) {
    if (discriminator->default_value.empty()) return std::nullopt;
    return std::string(discriminator->default_value);
  }
  if (!given->value.IsScalar()) return std::nullopt;
  const std::string& word = given->value.Scalar();
  const bool valid = discriminator->kind == Kind::boolean ? word == "true" || word == "false"
                                                          : contains(discriminator->choices, word);
  return valid ? std::optional(word) : std::nullopt;
}

SectionReader::Applies SectionReader::applies(const Parameter& parameter) const {
  Applies result = Applies::yes;
  for (const auto& condition : parameter.when) {
    const auto word = current_word(condition.key);
    if (!word) {
      result = Applies::unknown;
      continue;
    }
    if (!contains(condition.values, *word)) return Applies::no;
  }
  return result;
}

void SectionReader::check_presence() {
  for (const Parameter* parameter : section_parameters(section_)) {
    const Entry* given = entry(parameter->name);
    const Applies applicable = applies(*parameter);
    if (given != nullptr && applicable == Applies::no)
      report_not_applicable(*parameter, *given);
    else if (given == nullptr && parameter->required && applicable == Applies::yes)
      error(loc_, fmt::format("{} is required in {}", in_quotes(parameter->name), where_));
  }
}

// Names the first condition that fails, so the user knows which sibling decides.
void SectionReader::report_not_applicable(const Parameter& parameter, const Entry& given) const {
  for (const auto& condition : parameter.when) {
    const auto word = current_word(condition.key);
    if (!word || contains(condition.values, *word)) continue;
    error(context_->loc(given.key),
          fmt::format("{} applies only when '{}' is {} (here '{}')", in_quotes(parameter.name),
                      condition.key, join(condition.values, " or "), *word));
    return;
  }
}

void SectionReader::check_groups() {
  const auto fields = section_parameters(section_);
  std::vector<std::string_view> groups;
  for (const Parameter* parameter : fields) {
    if (parameter->one_of.empty() || contains(groups, parameter->one_of)) continue;
    groups.push_back(parameter->one_of);
    if (applies(*parameter) != Applies::yes) continue;  // members share their conditions
    std::vector<std::string_view> names;
    std::vector<const Entry*> given;
    for (const Parameter* member : fields) {
      if (member->one_of != parameter->one_of) continue;
      names.push_back(member->name);
      if (const Entry* e = entry(member->name)) given.push_back(e);
    }
    if (given.empty())
      error(loc_, fmt::format("one of {} is required in {}", alternatives(names), where_));
    else if (given.size() > 1)
      error(context_->loc(given[1]->key),
            fmt::format("give only one of {} in {}", alternatives(names), where_));
  }
}

// ---- Field lookup

const SectionReader::Entry* SectionReader::entry(std::string_view name) const {
  const auto found = entries_.find(name);
  return found == entries_.end() ? nullptr : &found->second;
}

std::optional<SourceLoc> SectionReader::value_loc(std::string_view name) const {
  const Entry* given = entry(name);
  if (given == nullptr) return std::nullopt;
  return context_->loc(given->value.IsNull() ? given->key : given->value);
}

const Parameter& SectionReader::parameter(std::string_view name,
                                          std::initializer_list<Kind> kinds) {
  const Parameter* found = find_parameter(section_, name);
  if (found == nullptr)
    throw std::logic_error(fmt::format("field '{}' is not in section '{}'", name, section_));
  if (std::find(kinds.begin(), kinds.end(), found->kind) == kinds.end())
    throw std::logic_error(fmt::format("field '{}' of '{}' is a {}, read as another kind", name,
                                       section_, kind_name(found->kind)));
  read_.insert(std::string(name));
  return *found;
}

std::optional<SectionReader::Value> SectionReader::lookup(std::string_view name,
                                                          std::initializer_list<Kind> kinds) {
  const Parameter& field = parameter(name, kinds);
  if (applies(field) == Applies::no) return std::nullopt;
  if (const Entry* given = entry(name)) {
    // A null value's mark points past it, to the next token: report at the key.
    const SourceLoc at = context_->loc(given->value.IsNull() ? given->key : given->value);
    return Value{given->value, at, &field, false};
  }
  if (field.default_value.empty()) return std::nullopt;
  return Value{YAML::Load(std::string(field.default_value)), loc_, &field, true};
}

SourceLoc SectionReader::node_loc(const Value& value, const YAML::Node& node) const {
  if (value.from_default || node.IsNull() || node.Mark().is_null()) return value.loc;
  return context_->loc(node);
}

std::optional<std::string> SectionReader::scalar(const Value& value, std::string_view expected) {
  if (value.node.IsScalar()) return value.node.Scalar();
  error(value.loc, fmt::format("{} expects {}, got {}", in_quotes(value.parameter->name), expected,
                               describe_node(value.node)));
  return std::nullopt;
}

bool SectionReader::check_range(const Parameter& field, const SourceLoc& loc,
                                std::string_view label, double value) {
  const std::string violated = field.range.violation(value, field.dimension);
  if (violated.empty()) return true;
  error(loc,
        fmt::format("{} must be {} (got {})", label, violated, format_si(value, field.dimension)));
  return false;
}

// ---- Scalars

std::optional<double> SectionReader::quantity(const Value& value, const YAML::Node& node,
                                              std::string_view label, Dimension dimension) {
  const SourceLoc at = node_loc(value, node);
  if (!node.IsScalar()) {
    error(at, fmt::format("{} expects {}, got {}", label, expected_text(dimension),
                          describe_node(node)));
    return std::nullopt;
  }
  const auto parsed = parse_quantity(node.Scalar(), dimension, label);
  if (!parsed.value) {
    error(at, parsed.error);
    return std::nullopt;
  }
  if (!check_range(*value.parameter, at, label, *parsed.value)) return std::nullopt;
  return parsed.value;
}

std::optional<long> SectionReader::integer(const Value& value, const YAML::Node& node,
                                           std::string_view label) {
  const SourceLoc at = node_loc(value, node);
  if (!node.IsScalar()) {
    error(at, fmt::format("{} expects a whole number, got {}", label, describe_node(node)));
    return std::nullopt;
  }
  const auto parsed = parse_quantity(node.Scalar(), Dimension::none, label);
  if (!parsed.value) {
    error(at, parsed.error);
    return std::nullopt;
  }
  const double number = *parsed.value;
  if (std::floor(number) != number) {
    error(at, fmt::format("{} must be a whole number (got {})", label, number));
    return std::nullopt;
  }
  if (std::abs(number) > kMaxExactInteger) {
    error(at, fmt::format("{} is too large (got {})", label, node.Scalar()));
    return std::nullopt;
  }
  if (!check_range(*value.parameter, at, label, number)) return std::nullopt;
  return static_cast<long>(number);
}

bool SectionReader::read(std::string_view name, double& out) {
  const auto value = lookup(name, {Kind::quantity});
  if (!value) return false;
  const auto number = quantity(*value, value->node, in_quotes(name), value->parameter->dimension);
  if (number) out = *number;
  return number.has_value();
}

bool SectionReader::read(std::string_view name, std::optional<double>& out) {
  const auto value = lookup(name, {Kind::quantity});
  if (!value) return false;
  const auto keyword = value->parameter->keyword;
  if (!keyword.empty() && value->node.IsScalar()) {
    const std::string& text = value->node.Scalar();
    if (text == keyword) {
      out.reset();
      return true;
    }
    // A word that is no number was meant as the keyword, not as a quantity.
    if (text.find_first_of("0123456789") == std::string::npos) {
      error(value->loc, fmt::format("'{}' expects {} or '{}', got '{}'", name,
                                    expected_text(value->parameter->dimension), keyword, text));
      return false;
    }
  }
  const auto number = quantity(*value, value->node, in_quotes(name), value->parameter->dimension);
  if (number) out = *number;
  return number.has_value();
}

bool SectionReader::read(std::string_view name, long& out) {
  const auto value = lookup(name, {Kind::integer});
  if (!value) return false;
  const auto number = integer(*value, value->node, in_quotes(name));
  if (number) out = *number;
  return number.has_value();
}

bool SectionReader::read(std::string_view name, int& out) {
  long wide = 0;
  if (!read(name, wide)) return false;
  if (wide < INT_MIN || wide > INT_MAX) {
    error(value_loc(name).value_or(loc_),
          fmt::format("{} is too large (got {})", in_quotes(name), wide));
    return false;
  }
  out = int(wide);
  return true;
}

bool SectionReader::read(std::string_view name, bool& out) {
  const auto value = lookup(name, {Kind::boolean});
  if (!value) return false;
  const auto word = scalar(*value, "true or false");
  if (!word) return false;
  if (*word != "true" && *word != "false") {
    error(value->loc, fmt::format("{} must be true or false (got '{}')", in_quotes(name), *word));
    return false;
  }
  out = *word == "true";
  return true;
}

bool SectionReader::read(std::string_view name, std::string& out) {
  const auto value = lookup(name, {Kind::name, Kind::choice, Kind::path, Kind::text});
  if (!value) return false;
  const Parameter& field = *value->parameter;
  if (field.kind == Kind::path || field.kind == Kind::text) {
    const auto path = scalar(*value, field.kind == Kind::path ? "a file path" : "a text");
    if (path && path->empty()) error(value->loc, fmt::format("{} is empty", in_quotes(name)));
    if (!path || path->empty()) return false;
    out = *path;
    return true;
  }
  const bool is_choice = field.kind == Kind::choice;
  const auto word = scalar(*value, is_choice ? "one of " + join(field.choices, ", ") : "a name");
  if (!word) return false;
  if (is_choice && !contains(field.choices, *word)) {
    std::string message = fmt::format("{} must be one of {} (got '{}'", in_quotes(name),
                                      join(field.choices, ", "), *word);
    if (const auto suggestion = closest_match(*word, field.choices))
      message += fmt::format("; did you mean '{}'?", *suggestion);
    error(value->loc, message + ")");
    return false;
  }
  if (!is_choice && !is_name(*word)) {
    error(value->loc, fmt::format("{} must be a name of letters, digits, '_' and '-' (got '{}')",
                                  in_quotes(name), *word));
    return false;
  }
  out = *word;
  return true;
}

bool SectionReader::read(std::string_view name, std::array<bool, 3>& out) {
  const auto value = lookup(name, {Kind::axes});
  if (!value) return false;
  const auto word = scalar(*value, "axes such as xz");
  if (!word) return false;
  std::array<bool, 3> axes{false, false, false};
  bool valid = !word->empty();
  for (const char c : *word) {
    const int axis = c - 'x';
    if (axis < 0 || axis > 2 || axes[size_t(axis)]) valid = false;
    if (!valid) break;
    axes[size_t(axis)] = true;
  }
  if (!valid) {
    error(value->loc,
          fmt::format("{} must be a non-empty combination of x, y, z, each at most once (got '{}')",
                      in_quotes(name), *word));
    return false;
  }
  out = axes;
  return true;
}

// ---- Vectors

template <class Item, class ReadItem>
std::optional<std::array<Item, 3>> SectionReader::triple(const Value& value, ReadItem read_item) {
  const std::string name = in_quotes(value.parameter->name);
  if (!value.node.IsSequence()) {
    error(value.loc, fmt::format("{} expects a list of 3 values [x, y, z], got {}", name,
                                 describe_node(value.node)));
    return std::nullopt;
  }
  if (value.node.size() != 3) {
    error(value.loc, fmt::format("{} expects 3 values [x, y, z], got {}", name, value.node.size()));
    return std::nullopt;
  }
  std::array<Item, 3> items{};
  bool ok = true;
  size_t i = 0;
  for (auto it = value.node.begin(); it != value.node.end(); ++it, ++i) {
    const auto item = read_item(*it, fmt::format("{} ({})", name, kAxes[i]));
    if (item) items[i] = *item;
    ok = ok && item.has_value();
  }
  if (!ok) return std::nullopt;
  return items;
}

std::optional<Eigen::Vector3d> SectionReader::vector(const Value& value, Dimension dimension) {
  if (value.parameter->uniform && value.node.IsScalar()) {  // `scale: 2` is [2, 2, 2]
    const auto one = quantity(value, value.node, in_quotes(value.parameter->name), dimension);
    if (!one) return std::nullopt;
    return Eigen::Vector3d::Constant(*one);
  }
  const auto items = triple<double>(value, [&](const YAML::Node& node, std::string_view label) {
    return quantity(value, node, label, dimension);
  });
  if (!items) return std::nullopt;
  return Eigen::Vector3d((*items)[0], (*items)[1], (*items)[2]);
}

bool SectionReader::read(std::string_view name, Eigen::Vector3d& out) {
  const auto value = lookup(name, {Kind::vector});
  if (!value) return false;
  const auto vec = vector(*value, value->parameter->dimension);
  if (vec) out = *vec;
  return vec.has_value();
}

bool SectionReader::read(std::string_view name, Eigen::Vector3d& out, Dimension dimension) {
  const auto value = lookup(name, {Kind::vector});
  if (!value) return false;
  const auto vec = vector(*value, dimension);
  if (vec) out = *vec;
  return vec.has_value();
}

bool SectionReader::read(std::string_view name, std::array<int, 3>& out) {
  const auto value = lookup(name, {Kind::integer_vector});
  if (!value) return false;
  const auto items = triple<long>(*value, [&](const YAML::Node& node, std::string_view label) {
    return integer(*value, node, label);
  });
  if (!items) return false;
  for (size_t i = 0; i < 3; ++i) {
    if ((*items)[i] < INT_MIN || (*items)[i] > INT_MAX) {
      error(value->loc, fmt::format("'{}' ({}) is too large", name, kAxes[i]));
      return false;
    }
    out[i] = int((*items)[i]);
  }
  return true;
}

bool SectionReader::read(std::string_view name, std::vector<int>& out) {
  const auto value = lookup(name, {Kind::integers});
  if (!value) return false;
  if (!value->node.IsSequence() || value->node.size() == 0) {
    const bool empty = value->node.IsSequence();
    error(value->loc, fmt::format("'{}' expects a list of whole numbers such as [1, 2], got {}",
                                  name, empty ? "an empty list" : describe_node(value->node)));
    return false;
  }
  std::vector<int> items;
  for (auto it = value->node.begin(); it != value->node.end(); ++it) {
    const auto item = integer(*value, *it, fmt::format("'{}' entry {}", name, items.size()));
    if (!item) return false;
    items.push_back(int(*item));
  }
  out = std::move(items);
  return true;
}

// ---- Node selectors

bool SectionReader::read(std::string_view name, NodeSelector& out) {
  out = NodeSelector{};
  out.loc = loc_;
  const auto value = lookup(name, {Kind::selector});
  if (!value) return entry(name) == nullptr;  // omitted: all nodes
  out.loc = value->loc;
  if (value->node.IsScalar()) return read_selector_text(*value, value->node.Scalar(), out);
  if (value->node.IsSequence()) return read_index_list(*value, out);
  if (value->node.IsMap()) return read_shape(*value, out);
  error(value->loc,
        fmt::format("'{}' expects {} (got {})", name, kSelectorForms, describe_node(value->node)));
  return false;
}

bool SectionReader::read_selector_text(const Value& value, const std::string& text,
                                       NodeSelector& out) {
  const std::string name = in_quotes(value.parameter->name);
  if (!looks_like_index_list(text)) {
    if (!is_name(text)) {
      error(value.loc, fmt::format("{} expects {} (got '{}')", name, kSelectorForms, text));
      return false;
    }
    out.kind = NodeSelector::Kind::named;
    out.name = text;
    return true;
  }
  std::vector<int> indices;
  bool ok = true;
  for (size_t start = 0; start <= text.size() && ok;) {
    const size_t comma = std::min(text.find(',', start), text.size());
    ok =
        read_index_token(value, trim(std::string_view(text).substr(start, comma - start)), indices);
    start = comma + 1;
  }
  if (!ok) return false;
  std::sort(indices.begin(), indices.end());
  indices.erase(std::unique(indices.begin(), indices.end()), indices.end());
  out.kind = NodeSelector::Kind::indices;
  out.indices = std::move(indices);
  return true;
}

// One comma-separated entry of an index list: "7" or "0-3".
bool SectionReader::read_index_token(const Value& value, std::string_view token,
                                     std::vector<int>& out) {
  const std::string name = in_quotes(value.parameter->name);
  if (token.empty()) {
    error(value.loc, fmt::format("{} has an empty entry in its index list", name));
    return false;
  }
  if (token.front() == '-' && all_digits(trim(token.substr(1)))) {
    error(value.loc, fmt::format("{} index {} is negative (indices start at 0)", name, token));
    return false;
  }
  const size_t dash = token.find('-');
  const auto first_text = trim(token.substr(0, dash));
  const auto last_text = dash == std::string_view::npos ? first_text : trim(token.substr(dash + 1));
  if (!all_digits(first_text) || !all_digits(last_text)) {
    error(value.loc, fmt::format("{} has a malformed entry '{}' (expected an index such as 7 or "
                                 "a range such as 0-3)",
                                 name, token));
    return false;
  }
  const auto first = index_value(first_text), last = index_value(last_text);
  if (!first || !last) {
    error(value.loc, fmt::format("{} index in '{}' is too large", name, token));
    return false;
  }
  if (*first > *last) {
    error(value.loc, fmt::format("{} range '{}' must have start <= end (write '{}-{}')", name,
                                 token, *last, *first));
    return false;
  }
  if (static_cast<long long>(out.size()) + *last - *first + 1 > kMaxSelectedIndices) {
    error(value.loc, fmt::format("{} selects more than {} indices; use a node set or a shape", name,
                                 kMaxSelectedIndices));
    return false;
  }
  for (int i = *first; i <= *last; ++i) {
    out.push_back(i);
    if (i == INT_MAX) break;  // ++i would overflow
  }
  return true;
}

bool SectionReader::read_index_list(const Value& value, NodeSelector& out) {
  const std::string name = in_quotes(value.parameter->name);
  if (value.node.size() == 0) {
    error(value.loc, fmt::format("{} lists no index", name));
    return false;
  }
  std::vector<int> indices;
  bool ok = true;
  size_t i = 0;
  for (auto it = value.node.begin(); it != value.node.end(); ++it, ++i) {
    const std::string label = fmt::format("'{}[{}]'", value.parameter->name, i);
    const auto index = integer(value, *it, label);
    if (index && *index < 0) {
      error(node_loc(value, *it),
            fmt::format("{} index {} is negative (indices start at 0)", name, *index));
    } else if (index && *index > INT_MAX) {
      error(node_loc(value, *it), fmt::format("{} index {} is too large", name, *index));
    } else if (index) {
      indices.push_back(int(*index));
      continue;
    }
    ok = false;
  }
  if (!ok) return false;
  std::sort(indices.begin(), indices.end());
  indices.erase(std::unique(indices.begin(), indices.end()), indices.end());
  out.kind = NodeSelector::Kind::indices;
  out.indices = std::move(indices);
  return true;
}

bool SectionReader::read_shape(const Value& value, NodeSelector& out) {
  SectionReader shape(*context_, value.node, "nodes", in_quotes(value.parameter->name), value.loc);
  auto box = shape.map("box");
  auto sphere = shape.map("sphere");
  auto half_space = shape.map("half_space");
  shape.done();
  // Absent shapes give nullopt (each has required fields); more than one was diagnosed.
  if (int(box.has_value()) + int(sphere.has_value()) + int(half_space.has_value()) != 1)
    return false;
  if (box) return read_box(*box, out);
  if (sphere) return read_sphere(*sphere, out);
  return read_half_space(*half_space, out);
}

bool SectionReader::read_box(SectionReader& box, NodeSelector& out) {
  const bool has_min = box.read("min", out.min);
  const bool has_max = box.read("max", out.max);
  box.done();
  if (!has_min || !has_max) return false;
  for (size_t i = 0; i < 3; ++i) {
    if (out.min[Eigen::Index(i)] <= out.max[Eigen::Index(i)]) continue;
    error(box.value_loc("max").value_or(box.loc()),
          fmt::format("'box' needs min <= max in each component ({}: min {} > max {})", kAxes[i],
                      format_si(out.min[Eigen::Index(i)], Dimension::length),
                      format_si(out.max[Eigen::Index(i)], Dimension::length)));
    return false;
  }
  out.kind = NodeSelector::Kind::box;
  return true;
}

bool SectionReader::read_sphere(SectionReader& sphere, NodeSelector& out) {
  const bool has_center = sphere.read("center", out.center);
  const bool has_radius = sphere.read("radius", out.radius);
  sphere.done();
  if (!has_center || !has_radius) return false;
  out.kind = NodeSelector::Kind::sphere;
  return true;
}

bool SectionReader::read_half_space(SectionReader& half_space, NodeSelector& out) {
  const bool has_point = half_space.read("point", out.point);
  Eigen::Vector3d normal = Eigen::Vector3d::Zero();
  const bool has_normal = half_space.read("normal", normal);
  half_space.done();
  if (!has_point || !has_normal) return false;
  if (normal.cwiseAbs().maxCoeff() == 0.0) {
    error(half_space.value_loc("normal").value_or(half_space.loc()),
          "'normal' must be a non-zero vector (got [0, 0, 0])");
    return false;
  }
  out.normal = normal.stableNormalized();  // stable: components may be huge or tiny
  out.kind = NodeSelector::Kind::half_space;
  return true;
}

// ---- Schedules

bool SectionReader::read(std::string_view name, Schedule& out) {
  const auto value = lookup(name, {Kind::schedule});
  if (!value) return false;
  if (!value->node.IsSequence() || value->node.size() == 0) {
    error(value->loc,
          fmt::format("'{}' expects a non-empty list of {{t, value}} events, got {}", name,
                      value->node.IsSequence() ? "an empty list" : describe_node(value->node)));
    return false;
  }
  return read_events(*value, out);
}

bool SectionReader::read_events(const Value& value, Schedule& out) {
  Schedule schedule;
  int previous_line = 0;
  bool ok = true;
  size_t i = 0;
  for (auto it = value.node.begin(); it != value.node.end(); ++it, ++i) {
    const std::string label = fmt::format("'{}[{}]'", value.parameter->name, i);
    const auto event = read_event(value, *it, label);
    if (event && !schedule.times.empty() && event->t <= schedule.times.back()) {
      error(event->loc,
            fmt::format("schedule times must be strictly increasing: {} has t = {} after t = {} "
                        "(line {})",
                        label, format_si(event->t, Dimension::time),
                        format_si(schedule.times.back(), Dimension::time), previous_line));
      ok = false;
    } else if (event) {
      schedule.times.push_back(event->t);
      schedule.values.push_back(event->value);
      previous_line = event->loc.line;
    } else {
      ok = false;
    }
  }
  if (ok) out = std::move(schedule);
  return ok;
}

// One {t, value} event; the value takes the unit of the scheduled field.
std::optional<SectionReader::Event> SectionReader::read_event(const Value& value,
                                                              const YAML::Node& node,
                                                              const std::string& label) {
  if (!node.IsMap()) {
    error(node_loc(value, node),
          fmt::format("{} expects a map {{t: ..., value: [x, y, z]}}, got {}", label,
                      describe_node(node)));
    return std::nullopt;
  }
  SectionReader reader(*context_, node, "schedule", label, context_->loc(node));
  Event event{0.0, Eigen::Vector3d::Zero(), {}};
  const bool has_t = reader.read("t", event.t);
  const bool has_value = reader.read("value", event.value, value.parameter->dimension);
  reader.done();
  event.loc = reader.value_loc("t").value_or(reader.loc());
  if (!has_t || !has_value) return std::nullopt;
  return event;
}

// ---- Nested maps and lists

std::optional<SectionReader> SectionReader::map(std::string_view name) {
  const Parameter& field = parameter(name, {Kind::map});
  if (applies(field) == Applies::no) return std::nullopt;
  const Entry* given = entry(name);
  if (given == nullptr) {
    // An omitted section with only optional fields still yields its defaults.
    if (has_required_fields(field.child)) return std::nullopt;
    return SectionReader(*context_, YAML::Node(), field.child, in_quotes(name),
                         SourceLoc{context_->file(), 0, 0});
  }
  if (given->value.IsNull() || given->value.IsMap())
    return SectionReader(*context_, given->value, field.child, in_quotes(name),
                         context_->loc(given->key));
  error(context_->loc(given->value),
        fmt::format("'{}' expects a map of fields, got {}", name, describe_node(given->value)));
  return std::nullopt;
}

void SectionReader::items(std::string_view name,
                          const std::function<void(SectionReader&)>& read_entry) {
  const Parameter& field = parameter(name, {Kind::list});
  const Entry* given = entry(name);
  if (given == nullptr) return;  // a missing required list was diagnosed with the keys
  if (!given->value.IsNull() && !given->value.IsSequence()) {
    error(context_->loc(given->value),
          fmt::format("'{}' expects a list, got {}", name, describe_node(given->value)));
    return;
  }
  size_t count = 0;
  for (auto it = given->value.begin(); it != given->value.end(); ++it, ++count) {
    const std::string label = fmt::format("'{}[{}]'", name, count);
    if (!it->IsMap()) {
      const SourceLoc at = it->IsNull() ? context_->loc(given->key) : context_->loc(*it);
      error(at, fmt::format("{} expects a map of fields, got {}", label, describe_node(*it)));
      continue;
    }
    SectionReader item(*context_, *it, field.child, label, context_->loc(*it));
    read_entry(item);
  }
  if (field.range.min && double(count) < *field.range.min)
    error(context_->loc(given->key),
          fmt::format("'{}' needs at least {} entr{} (got {})", name, *field.range.min,
                      *field.range.min == 1 ? "y" : "ies",
                      count == 0 ? "none" : fmt::format("{}", count)));
}

void SectionReader::done() const {
  for (const Parameter* field : section_parameters(section_))
    if (!read_.contains(field->name))
      throw std::logic_error(
          fmt::format("field '{}' of section '{}' is in the parameter table but "
                      "never read by the scene parser",
                      field->name, section_));
}

}  // namespace phymul::io
