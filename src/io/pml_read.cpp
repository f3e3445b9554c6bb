// CamiTK PML physical models (camitk.hpp): atoms, exclusive and informative components and
// their cells, read with pugixml.
#include <fmt/format.h>
#include <fmt/ranges.h>

#include <algorithm>
#include <cctype>
#include <climits>
#include <fstream>
#include <optional>
#include <set>
#include <sstream>
#include <tuple>
#include <unordered_map>

#include "io/xml_source.hpp"
#include "phymul/camitk.hpp"

namespace phymul {
namespace {

// CamiTK's geometric types; those without a CellType make no cell of an object.
struct CellKind {
  std::string_view name;
  std::optional<CellType> type;
  int nodes;  // exact count; negative: at least -nodes
};

constexpr std::array<CellKind, 10> kCellKinds{{
    {"TETRAHEDRON", CellType::tetra, 4},
    {"HEXAHEDRON", CellType::hexa, 8},
    {"WEDGE", CellType::wedge, 6},
    {"TRIANGLE", CellType::triangle, 3},
    {"QUAD", CellType::quad, 4},
    {"LINE", std::nullopt, 2},
    {"POLY_LINE", std::nullopt, -2},
    {"POLY_VERTEX", std::nullopt, -1},
    {"ATOM", std::nullopt, 1},
    {"PYRAMID", std::nullopt, 5},
}};

constexpr int kMaxDepth = 64;  // multiComponents in one another: the reader recurses

const CellKind* find_kind(std::string_view name) {
  for (const CellKind& k : kCellKinds)
    if (k.name == name) return &k;
  return nullptr;
}

// A cell as read: its kind and atoms (positions in PmlModel::atoms).
struct ReadCell {
  const CellKind* kind = nullptr;
  std::vector<int> atoms;
};

// The same cell listed the other way round: CamiTK fixes the nodes' topology (VTK's) but
// not the orientation, which VTK and phymul take from the order.
void flip(Cell& c) {
  auto& n = c.nodes;
  if (c.type == CellType::tetra) std::swap(n[1], n[2]);
  if (c.type == CellType::wedge) std::rotate(n.begin(), n.begin() + 3, n.begin() + 6);
  if (c.type == CellType::hexa) std::rotate(n.begin(), n.begin() + 4, n.begin() + 8);
}

class PmlReader {
 public:
  PmlReader(std::string_view text, const std::string& name, double divisor)
      : src_(text, name), divisor_(divisor) {}
  PmlModel read();

 private:
  void read_atoms(const pugi::xml_node& atoms);
  void read_atom(const pugi::xml_node& atom);
  void read_components(const pugi::xml_node& parent, bool exclusive, std::vector<int>& members,
                       int depth);
  void read_structural(const pugi::xml_node& sc, bool exclusive);
  void read_cell(const pugi::xml_node& node, int component);
  void add_cell(int component, int cell);
  int atom(const pugi::xml_node& ref) const;
  void resolve_cell_refs();
  void finish_multi(int multi, const std::vector<int>& members);
  void note_counts(const pugi::xml_node& root);
  void note_unread(const pugi::xml_node& node, std::initializer_list<std::string_view> read,
                   std::set<std::string>& unread);

  xml::Source src_;
  double divisor_;
  PmlModel model_;
  std::unordered_map<long long, int> atom_at_;  // atom index -> position
  std::vector<pugi::xml_node> atom_nodes_;      // per position, for messages
  std::vector<ReadCell> cells_;
  std::unordered_map<long long, int> cell_at_;  // cellProperties index -> cells_
  struct CellRef {
    int component;
    pugi::xml_node node;
  };
  std::vector<CellRef> cell_refs_;
  int reordered_ = 0, cell_count_ = 0;
  std::string first_reordered_;
  std::set<std::string> unread_atom_, unread_component_;
};

PmlModel PmlReader::read() {
  const pugi::xml_node root = src_.document().document_element();
  if (std::string_view(root.name()) != "physicalModel")
    src_.fail(root, fmt::format("expected <physicalModel> as the root element (a CamiTK PML "
                                "file), found {}",
                                xml::tag(root)));
  model_.name = root.attribute("name").value();
  const pugi::xml_node atoms = root.child("atoms");
  if (!atoms) src_.fail(root, "<physicalModel> has no <atoms>");
  read_atoms(atoms);
  for (const char* list : {"exclusiveComponents", "informativeComponents"}) {
    std::vector<int> members;
    read_components(root.child(list), std::string_view(list) == "exclusiveComponents", members, 0);
  }
  resolve_cell_refs();
  for (PmlComponent& c : model_.components) {
    std::sort(c.atoms.begin(), c.atoms.end());
    c.atoms.erase(std::unique(c.atoms.begin(), c.atoms.end()), c.atoms.end());
  }
  note_counts(root);
  if (reordered_ > 0)
    model_.notes.push_back(fmt::format(
        "{}: {} cells listed inside out (CamiTK does not fix the orientation) were reordered as "
        "VTK's, the first {}",
        src_.name(), reordered_, first_reordered_));
  if (!unread_atom_.empty())
    model_.notes.push_back(
        fmt::format("{}: atom properties not read: {} (masses come from the "
                    "scene's material)",
                    src_.name(), fmt::join(unread_atom_, ", ")));
  if (!unread_component_.empty())
    model_.notes.push_back(
        fmt::format("{}: component properties not read: {} (the scene gives "
                    "each object's type and material)",
                    src_.name(), fmt::join(unread_component_, ", ")));
  return std::move(model_);
}

void PmlReader::read_atoms(const pugi::xml_node& atoms) {
  for (const pugi::xml_node& child : atoms.children()) {
    const std::string_view name = child.name();
    if (name == "atom") {
      read_atom(child);
    } else if (name == "structuralComponent") {
      long long listed = 0;
      for (const pugi::xml_node& atom : child.children("atom")) read_atom(atom), ++listed;
      if (const pugi::xml_node n = child.child("nrOfStructures"))
        if (src_.integer(n, "value", 0, LLONG_MAX) != listed)
          model_.notes.push_back(src_.at(n, fmt::format("<nrOfStructures> says {}, the component "
                                                        "lists {} atoms",
                                                        n.attribute("value").value(), listed)));
    } else if (child.type() == pugi::node_element) {
      src_.fail(child, fmt::format("unexpected {} in <atoms> (expected <structuralComponent> "
                                   "or <atom>)",
                                   xml::tag(child)));
    }
  }
  if (model_.atoms.empty()) src_.fail(atoms, "<atoms> holds no <atom>");
}

void PmlReader::read_atom(const pugi::xml_node& atom) {
  const pugi::xml_node p = atom.child("atomProperties");
  if (!p) src_.fail(atom, "<atom> has no <atomProperties>");
  const long long index = src_.integer(p, "index", 0, INT_MAX);
  const Vec3 x(src_.number(p, "x"), src_.number(p, "y"), src_.number(p, "z"));
  note_unread(p, {"index", "x", "y", "z"}, unread_atom_);
  const auto [previous, inserted] = atom_at_.emplace(index, int(model_.atoms.size()));
  if (!inserted)
    src_.fail(p, fmt::format("atom index {} is used twice (first at line {})", index,
                             src_.where(atom_nodes_[size_t(previous->second)]).first));
  model_.atom_ids.push_back(int(index));
  model_.atoms.push_back(x / divisor_);
  atom_nodes_.push_back(p);
}

// The components under `parent`, depth first; `members` gets the structural components
// read (for the multiComponent that holds them).
void PmlReader::read_components(const pugi::xml_node& parent, bool exclusive,
                                std::vector<int>& members, int depth) {
  if (depth > kMaxDepth)
    src_.fail(parent, fmt::format("components nested deeper than {} levels", kMaxDepth));
  for (const pugi::xml_node& child : parent.children()) {
    const std::string_view name = child.name();
    if (name == "multiComponent") {
      const int multi = int(model_.components.size());
      PmlComponent m;
      m.name = child.attribute("name").value();
      m.exclusive = exclusive, m.multi = true;
      std::tie(m.line, m.column) = src_.where(child);
      model_.components.push_back(std::move(m));
      std::vector<int> below;
      read_components(child, exclusive, below, depth + 1);
      finish_multi(multi, below);
      members.insert(members.end(), below.begin(), below.end());
    } else if (name == "structuralComponent") {
      members.push_back(int(model_.components.size()));
      read_structural(child, exclusive);
    } else if (child.type() == pugi::node_element) {
      src_.fail(child, fmt::format("unexpected {} in {} (expected <multiComponent> or "
                                   "<structuralComponent>)",
                                   xml::tag(child), xml::tag(parent)));
    }
  }
}

void PmlReader::read_structural(const pugi::xml_node& sc, bool exclusive) {
  const int c = int(model_.components.size());
  PmlComponent made;
  made.name = sc.attribute("name").value();
  made.exclusive = exclusive;
  std::tie(made.line, made.column) = src_.where(sc);
  model_.components.push_back(std::move(made));
  note_unread(sc, {"name", "mode"}, unread_component_);
  long long listed = 0;
  for (const pugi::xml_node& child : sc.children()) {
    const std::string_view name = child.name();
    if (name == "cell") {
      read_cell(child, c), ++listed;
    } else if (name == "atomRef") {
      model_.components[size_t(c)].atoms.push_back(atom(child)), ++listed;
    } else if (name == "cellRef") {
      cell_refs_.push_back({c, child}), ++listed;
    } else if (name != "nrOfStructures" && name != "color" && child.type() == pugi::node_element) {
      src_.fail(child, fmt::format("unexpected {} in <structuralComponent> (expected <cell>, "
                                   "<atomRef>, <cellRef>, <color> or <nrOfStructures>)",
                                   xml::tag(child)));
    }
  }
  if (const pugi::xml_node n = sc.child("nrOfStructures"))
    if (src_.integer(n, "value", 0, LLONG_MAX) != listed)
      model_.notes.push_back(src_.at(
          n, fmt::format("<nrOfStructures> says {}, component '{}' "
                         "lists {}",
                         n.attribute("value").value(), model_.components[size_t(c)].name, listed)));
}

void PmlReader::read_cell(const pugi::xml_node& node, int component) {
  const pugi::xml_node p = node.child("cellProperties");
  if (!p) src_.fail(node, "<cell> has no <cellProperties>");
  const std::string_view type = xml::trim(p.attribute("type").value());
  const CellKind* kind = find_kind(type);
  if (!kind) {
    std::vector<std::string_view> known;
    for (const CellKind& k : kCellKinds) known.push_back(k.name);
    src_.fail(p, fmt::format("<cellProperties> type '{}' is not a CamiTK cell type (expected {})",
                             type, fmt::join(known, ", ")));
  }
  ReadCell cell{kind, {}};
  for (const pugi::xml_node& ref : node.children("atomRef")) cell.atoms.push_back(atom(ref));
  const int n = int(cell.atoms.size());
  if ((kind->nodes > 0 && n != kind->nodes) || (kind->nodes < 0 && n < -kind->nodes))
    src_.fail(node, fmt::format("a {} cell needs {}{} <atomRef>, it lists {}", kind->name,
                                kind->nodes < 0 ? "at least " : "", std::abs(kind->nodes), n));
  const int id = int(cells_.size());
  if (p.attribute("index")) {
    const long long index = src_.integer(p, "index", 0, LLONG_MAX);
    if (!cell_at_.emplace(index, id).second)
      src_.fail(p, fmt::format("cell index {} is used twice", index));
  }
  cells_.push_back(std::move(cell));
  ++cell_count_;
  add_cell(component, id);
  // Oriented once, where it is read: a cellRef adds the same cell.
  if (kind->type && is_volumetric(*kind->type)) {
    PmlComponent& c = model_.components[size_t(component)];
    Cell& made = c.cells.back();
    if (cell_measure(model_.atoms, made) < 0.0) {
      flip(made);
      std::copy_n(made.nodes.begin(), node_count(made.type), cells_[size_t(id)].atoms.begin());
      if (reordered_++ == 0) first_reordered_ = src_.at(node, "here");
    }
  }
}

// The cell `cell` (of cells_) joins `component`: its atoms, and the cell where it makes one.
void PmlReader::add_cell(int component, int cell) {
  PmlComponent& c = model_.components[size_t(component)];
  const ReadCell& r = cells_[size_t(cell)];
  c.atoms.insert(c.atoms.end(), r.atoms.begin(), r.atoms.end());
  if (!r.kind->type) {
    if (std::find(c.other_cells.begin(), c.other_cells.end(), r.kind->name) == c.other_cells.end())
      c.other_cells.emplace_back(r.kind->name);
    return;
  }
  Cell made;
  made.type = *r.kind->type;
  std::copy(r.atoms.begin(), r.atoms.end(), made.nodes.begin());
  c.cells.push_back(made);
}

int PmlReader::atom(const pugi::xml_node& ref) const {
  const long long index = src_.integer(ref, "index", 0, LLONG_MAX);
  const auto it = atom_at_.find(index);
  if (it == atom_at_.end())
    src_.fail(ref, fmt::format("<atomRef> index {} names no atom of <atoms> ({} atoms)", index,
                               model_.atoms.size()));
  return it->second;
}

// cellRef names a cell by its <cellProperties index>, wherever in the file it is.
void PmlReader::resolve_cell_refs() {
  for (const CellRef& ref : cell_refs_) {
    const long long index = src_.integer(ref.node, "index", 0, LLONG_MAX);
    const auto it = cell_at_.find(index);
    if (it == cell_at_.end())
      src_.fail(ref.node, fmt::format("<cellRef> index {} names no cell (no <cellProperties "
                                      "index=\"{}\">)",
                                      index, index));
    add_cell(ref.component, it->second);
  }
}

void PmlReader::finish_multi(int multi, const std::vector<int>& members) {
  PmlComponent m = std::move(model_.components[size_t(multi)]);
  for (int i : members) {
    const PmlComponent& c = model_.components[size_t(i)];
    m.cells.insert(m.cells.end(), c.cells.begin(), c.cells.end());
    m.atoms.insert(m.atoms.end(), c.atoms.begin(), c.atoms.end());
    for (const std::string& t : c.other_cells)
      if (std::find(m.other_cells.begin(), m.other_cells.end(), t) == m.other_cells.end())
        m.other_cells.push_back(t);
  }
  model_.components[size_t(multi)] = std::move(m);
}

// The header's counts are hints for CamiTK's allocations, and hand-written files get them
// wrong: what they say and what the file holds are compared, and a difference is a note.
void PmlReader::note_counts(const pugi::xml_node& root) {
  long long structural[2] = {0, 0};
  for (const PmlComponent& c : model_.components)
    if (!c.multi) ++structural[c.exclusive ? 0 : 1];
  const std::pair<const char*, long long> counts[] = {{"nrOfAtoms", (long long)model_.atoms.size()},
                                                      {"nrOfExclusiveComponents", structural[0]},
                                                      {"nrOfInformativeComponents", structural[1]},
                                                      {"nrOfCells", cell_count_}};
  for (const auto& [attribute, found] : counts)
    if (root.attribute(attribute))
      if (const long long said = src_.integer(root, attribute, 0, LLONG_MAX); said != found)
        model_.notes.push_back(src_.at(root, fmt::format("<physicalModel> {} says {}, the file "
                                                         "holds {}",
                                                         attribute, said, found)));
}

void PmlReader::note_unread(const pugi::xml_node& node,
                            std::initializer_list<std::string_view> read,
                            std::set<std::string>& unread) {
  for (const pugi::xml_attribute& a : node.attributes())
    if (std::find(read.begin(), read.end(), std::string_view(a.name())) == read.end())
      unread.insert(a.name());
}

std::string component_list(const PmlModel& pml) {
  std::vector<std::string> names;
  for (const PmlComponent& c : pml.components)
    if (c.exclusive && !c.cells.empty()) names.push_back(fmt::format("'{}'", c.name));
  return names.empty() ? "none" : fmt::format("{}", fmt::join(names, ", "));
}

const PmlComponent& choose(const PmlModel& pml, const std::string& component,
                           const std::string& file) {
  if (!component.empty()) {
    const PmlComponent* c = pml.find(component);
    if (!c)
      throw MeshFileError(file, 0, 0,
                          fmt::format("no component '{}' (exclusive components with cells: {})",
                                      component, component_list(pml)));
    return *c;
  }
  const PmlComponent* only = nullptr;
  for (const PmlComponent& c : pml.components)
    if (c.exclusive && !c.multi && (!c.cells.empty() || !c.other_cells.empty())) {
      if (only)
        throw MeshFileError(file, 0, 0,
                            fmt::format("the file has several exclusive components with cells "
                                        "({}): name one with 'component'",
                                        component_list(pml)));
      only = &c;
    }
  if (!only) throw MeshFileError(file, 0, 0, "no exclusive component holds cells");
  return *only;
}

}  // namespace

// Letters, digits, '_' and '-' as the scene's node-set names are; '_' for the rest.
std::string pml_node_set_name(std::string_view name) {
  std::string out;
  for (const char c : xml::trim(name))
    out += std::isalnum(static_cast<unsigned char>(c)) || c == '_' || c == '-' ? c : '_';
  return out;
}

const PmlComponent* PmlModel::find(std::string_view component) const {
  for (const PmlComponent& c : components)
    if (c.name == component || xml::trim(c.name) == xml::trim(component)) return &c;
  return nullptr;
}

PmlModel parse_pml(std::string_view text, const std::string& name, double divisor) {
  return PmlReader(text, name, divisor).read();
}

PmlModel read_pml(const std::filesystem::path& path, double divisor) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw MeshFileError(path.string(), 0, 0, "cannot open the PML file");
  std::ostringstream s;
  s << in.rdbuf();
  return parse_pml(s.str(), path.string(), divisor);
}

Mesh pml_object_mesh(const PmlModel& pml, const std::string& component, std::vector<int>* atom_ids,
                     const std::string& file) {
  const PmlComponent& c = choose(pml, component, file);
  if (!c.other_cells.empty())
    throw MeshFileError(file, c.line, c.column,
                        fmt::format("component '{}' holds {} cells, which make no object (an "
                                    "object's cells are TETRAHEDRON, HEXAHEDRON, WEDGE, TRIANGLE "
                                    "or QUAD)",
                                    c.name, fmt::join(c.other_cells, ", ")));
  if (c.cells.empty())
    throw MeshFileError(file, c.line, c.column,
                        fmt::format("component '{}' holds no cell", c.name));
  // Only the atoms its cells use, in file order.
  std::vector<int> local(pml.atoms.size(), -1);
  for (const Cell& cell : c.cells)
    for (int a : cell.node_span()) local[size_t(a)] = 0;
  Mesh mesh;
  if (atom_ids) atom_ids->clear();
  for (size_t a = 0; a < local.size(); ++a)
    if (local[a] == 0) {
      local[a] = int(mesh.points.size());
      mesh.points.push_back(pml.atoms[a]);
      if (atom_ids) atom_ids->push_back(pml.atom_ids[a]);
    }
  for (Cell cell : c.cells) {
    for (int k = 0; k < node_count(cell.type); ++k)
      cell.nodes[size_t(k)] = local[size_t(cell.nodes[size_t(k)])];
    mesh.cells.push_back(cell);
  }
  for (const PmlComponent& named : pml.components) {
    if (named.exclusive || named.multi) continue;  // the informative structural components
    std::vector<int> set;
    for (int a : named.atoms)
      if (local[size_t(a)] >= 0) set.push_back(local[size_t(a)]);
    const std::string key = pml_node_set_name(named.name);
    if (set.empty() || key.empty()) continue;
    std::vector<int>& out = mesh.node_sets[key];
    out.insert(out.end(), set.begin(), set.end());
    std::sort(out.begin(), out.end());
    out.erase(std::unique(out.begin(), out.end()), out.end());
  }
  return mesh;
}

}  // namespace phymul
