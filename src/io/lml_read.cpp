// CamiTK LML loads (camitk.hpp): translations, forces and pressures with their value events,
// directions and units, read with pugixml into SI.
#include <fmt/format.h>
#include <fmt/ranges.h>

#include <algorithm>
#include <cctype>
#include <charconv>
#include <climits>
#include <cmath>
#include <fstream>
#include <numeric>
#include <sstream>

#include "io/units.hpp"
#include "io/xml_source.hpp"
#include "phymul/camitk.hpp"

namespace phymul {
namespace {

constexpr size_t kMaxAtoms = 10'000'000;  // in one <appliedTo>: guards the memory ranges take

struct LmlUnit {
  std::string_view symbol;
  double scale, divisor;  // SI = value * scale / divisor, as the scene's units
};

struct LmlType {
  std::string_view name;
  LmlLoad::Type type;
  std::string_view default_unit;
  std::vector<LmlUnit> units;
};

// CamiTK's units (mm, microm, nm; N, kN, pN; kPa, mmHg) and the scene's SI ones.
const std::vector<LmlType>& types() {
  static const std::vector<LmlType> table{
      {"Translation",
       LmlLoad::Type::translation,
       "mm",
       {{"mm", 1, 1e3},
        {"microm", 1, 1e6},
        {"um", 1, 1e6},
        {"nm", 1, 1e9},
        {"cm", 1, 1e2},
        {"m", 1, 1}}},
      {"Force",
       LmlLoad::Type::force,
       "N",
       {{"N", 1, 1}, {"kN", 1e3, 1}, {"mN", 1, 1e3}, {"pN", 1, 1e12}}},
      {"Pressure",
       LmlLoad::Type::pressure,
       "kPa",
       {{"kPa", 1e3, 1}, {"Pa", 1, 1}, {"MPa", 1e6, 1}, {"mmHg", 133.322387415, 1}}},
  };
  return table;
}

class LmlReader {
 public:
  LmlReader(std::string_view text, const std::string& name) : src_(text, name) {}
  std::vector<LmlLoad> read();

 private:
  LmlLoad load(const pugi::xml_node& node);
  void applied_to(const pugi::xml_node& node, LmlLoad& load);
  void direction(const pugi::xml_node& node, LmlLoad& load);
  void events(const pugi::xml_node& node, const LmlType& type, LmlLoad& load);

  xml::Source src_;
};

std::vector<LmlLoad> LmlReader::read() {
  const pugi::xml_node root = src_.document().document_element();
  if (std::string_view(root.name()) != "loads")
    src_.fail(root, fmt::format("expected <loads> as the root element (a CamiTK LML file), found "
                                "{}",
                                xml::tag(root)));
  std::vector<LmlLoad> loads;
  for (const pugi::xml_node& child : root.children()) {
    if (child.type() != pugi::node_element) continue;
    if (std::string_view(child.name()) != "load")
      src_.fail(child, fmt::format("unexpected {} in <loads> (expected <load>)", xml::tag(child)));
    loads.push_back(load(child));
  }
  return loads;
}

LmlLoad LmlReader::load(const pugi::xml_node& node) {
  pugi::xml_attribute kind = node.attribute("xsi:type");
  if (!kind) kind = node.attribute("type");
  const std::string_view name = xml::trim(kind.value());
  if (name == "Rotation")
    src_.fail(node,
              "<load> of type Rotation is not supported: phymul prescribes translations "
              "of nodes (a rigid object turns by objects[].motion.rotation in the scene)");
  const auto& table = types();
  const auto type =
      std::find_if(table.begin(), table.end(), [&](const LmlType& t) { return t.name == name; });
  if (type == table.end())
    src_.fail(node, fmt::format("<load> xsi:type '{}' is not a load type (expected Translation, "
                                "Force or Pressure)",
                                name));
  LmlLoad load;
  load.type = type->type;
  load.line = src_.where(node).first;
  for (const pugi::xml_node& child : node.children()) {
    const std::string_view tag = child.name();
    if (child.type() != pugi::node_element) continue;
    if (tag == "appliedTo") {
      applied_to(child, load);
    } else if (tag == "direction") {
      direction(child, load);
    } else if (tag == "unit") {
      load.unit = xml::trim(child.text().get());
    } else if (tag != "valueEvent") {
      src_.fail(child, fmt::format("unexpected {} in <load> (expected <appliedTo>, <valueEvent>, "
                                   "<direction> or <unit>)",
                                   xml::tag(child)));
    }
  }
  if (load.atoms.empty() && load.names.empty())
    src_.fail(node, "<load> has no <appliedTo> (the atoms it applies to, as \"0-3,7\")");
  if (load.type != LmlLoad::Type::pressure &&
      std::all_of(load.axes.begin(), load.axes.end(),
                  [](LmlLoad::Axis a) { return a == LmlLoad::Axis::free; }))
    src_.fail(node, fmt::format("<load> of type {} has no <direction x=\"..\" y=\"..\" z=\"..\"/>",
                                name));
  events(node, *type, load);
  return load;
}

// "0-3,7" as CamiTK's target lists: indices and ranges, or component names, "*" for all.
void LmlReader::applied_to(const pugi::xml_node& node, LmlLoad& load) {
  const std::string text(xml::trim(node.text().get()));
  if (text.empty()) src_.fail(node, "<appliedTo> is empty");
  for (size_t start = 0; start <= text.size();) {
    const size_t comma = std::min(text.find(',', start), text.size());
    const std::string_view token = xml::trim(std::string_view(text).substr(start, comma - start));
    start = comma + 1;
    if (token.empty()) src_.fail(node, "<appliedTo> has an empty entry");
    const size_t dash = token.find('-', 1);
    const auto whole = [&](std::string_view t) -> std::optional<int> {
      t = xml::trim(t);
      int v = 0;
      const auto [end, ec] = std::from_chars(t.data(), t.data() + t.size(), v);
      if (t.empty() || ec != std::errc{} || end != t.data() + t.size() || v < 0)
        return std::nullopt;
      return v;
    };
    const auto first = whole(token.substr(0, dash));
    const auto last = dash == std::string_view::npos ? first : whole(token.substr(dash + 1));
    if (token.front() == '-')
      src_.fail(node,
                fmt::format("<appliedTo> entry '{}' is negative (atom indices start at 0)", token));
    if (!std::isdigit(static_cast<unsigned char>(token.front()))) {
      load.names.emplace_back(token);  // a component's name
    } else if (!first || !last || *last < *first) {
      src_.fail(node, fmt::format("<appliedTo> entry '{}' is not an atom index or a range "
                                  "first-last",
                                  token));
    } else {
      if (load.atoms.size() + size_t(*last - *first) >= kMaxAtoms)
        src_.fail(node, fmt::format("<appliedTo> selects more than {} atoms", kMaxAtoms));
      for (long long i = *first; i <= *last; ++i) load.atoms.push_back(int(i));
    }
  }
  std::sort(load.atoms.begin(), load.atoms.end());
  load.atoms.erase(std::unique(load.atoms.begin(), load.atoms.end()), load.atoms.end());
}

// Per axis: absent (free), "NULL" (held at 0) or a number (the value's factor).
void LmlReader::direction(const pugi::xml_node& node, LmlLoad& load) {
  if (node.attribute("toward"))
    src_.fail(node, "<direction toward=...> (towards an atom) is not supported: give x, y, z");
  for (int k = 0; k < 3; ++k) {
    const char* axis = k == 0 ? "x" : k == 1 ? "y" : "z";
    const pugi::xml_attribute a = node.attribute(axis);
    if (!a) continue;
    if (xml::trim(a.value()) == "NULL") {
      load.axes[size_t(k)] = LmlLoad::Axis::null;
    } else {
      load.direction[k] = src_.number(node, axis);
      load.axes[size_t(k)] = LmlLoad::Axis::given;
    }
  }
}

void LmlReader::events(const pugi::xml_node& node, const LmlType& type, LmlLoad& load) {
  if (load.unit.empty()) load.unit = type.default_unit;
  const auto unit = std::find_if(type.units.begin(), type.units.end(),
                                 [&](const LmlUnit& u) { return u.symbol == load.unit; });
  if (unit == type.units.end()) {
    std::vector<std::string_view> known;
    for (const LmlUnit& u : type.units) known.push_back(u.symbol);
    src_.fail(node.child("unit"), fmt::format("<unit> '{}' is not a unit of a {} (expected {})",
                                              load.unit, type.name, fmt::join(known, ", ")));
  }
  std::vector<std::pair<double, double>> events;  // date, SI value
  std::vector<pugi::xml_node> at;
  for (const pugi::xml_node& e : node.children("valueEvent")) {
    const double date = src_.number(e, "date");
    if (date < 0.0) src_.fail(e, fmt::format("<valueEvent> date must be >= 0 s, found {}", date));
    const double value = src_.number(e, "value") * unit->scale / unit->divisor;
    // In SI and along the direction, it must stay a number.
    if (!std::isfinite(value) || !std::isfinite(value * load.direction.cwiseAbs().maxCoeff()))
      src_.fail(e, fmt::format("<valueEvent> value {} {} is too large",
                               e.attribute("value").value(), load.unit));
    events.emplace_back(date, value);
    at.push_back(e);
  }
  if (events.empty()) src_.fail(node, "<load> has no <valueEvent date=\"..\" value=\"..\"/>");
  // CamiTK sorts the events by date; two at one date would make the value ambiguous.
  std::vector<size_t> order(events.size());
  std::iota(order.begin(), order.end(), size_t{0});
  std::stable_sort(order.begin(), order.end(),
                   [&](size_t a, size_t b) { return events[a].first < events[b].first; });
  for (size_t k = 0; k < order.size(); ++k) {
    if (k > 0 && events[order[k]].first == events[order[k - 1]].first)
      src_.fail(at[order[k]],
                fmt::format("two <valueEvent> at date {} (the other at line {})",
                            events[order[k]].first, src_.where(at[order[k - 1]]).first));
    load.dates.push_back(events[order[k]].first);
    load.values.push_back(events[order[k]].second);
  }
}

}  // namespace

std::vector<LmlLoad> parse_lml(std::string_view text, const std::string& name) {
  return LmlReader(text, name).read();
}

std::vector<LmlLoad> read_lml(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw MeshFileError(path.string(), 0, 0, "cannot open the LML file");
  std::ostringstream s;
  s << in.rdbuf();
  return parse_lml(s.str(), path.string());
}

}  // namespace phymul
