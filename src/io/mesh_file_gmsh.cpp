// Gmsh ASCII meshes, format 4.1 (entity blocks) and 2.2 (one line per node and element).
#include <fmt/format.h>

#include <algorithm>
#include <climits>
#include <map>
#include <optional>
#include <set>
#include <unordered_map>

#include "io/mesh_text.hpp"
#include "phymul/mesh_io.hpp"

namespace phymul {
namespace {

using mesh_io::Lexer;
using mesh_io::Token;

constexpr long long kMaxCount = INT_MAX / 8;

struct ElementType {
  int code, nodes, dimension;
  std::optional<CellType> cell;  // nullopt: only for node sets (points, lines)
};

// Linear elements only; Gmsh's hexahedron and tetrahedron use VTK's node order.
constexpr ElementType kTypes[] = {{15, 1, 0, std::nullopt},      {1, 2, 1, std::nullopt},
                                  {2, 3, 2, CellType::triangle}, {3, 4, 2, CellType::quad},
                                  {4, 4, 3, CellType::tetra},    {5, 8, 3, CellType::hexa},
                                  {6, 6, 3, CellType::wedge}};

struct Element {
  const ElementType* type;
  std::array<long long, 8> nodes;  // node tags
  std::vector<int> physical;       // physical group tags
  Token at;
};

class GmshReader {
 public:
  GmshReader(std::string_view text, const std::string& name, double divisor)
      : in_(text, name), divisor_(divisor) {}

  Mesh read() {
    read_format();
    while (!in_.at_end()) {
      const Token section = in_.next("a section such as $Nodes");
      if (section.text == "$PhysicalNames")
        read_physical_names();
      else if (section.text == "$Entities" && version_ == 4)
        read_entities();
      else if (section.text == "$Nodes")
        version_ == 4 ? read_nodes_41() : read_nodes_22();
      else if (section.text == "$Elements")
        version_ == 4 ? read_elements_41() : read_elements_22();
      else if (section.text.starts_with("$") && !section.text.starts_with("$End"))
        skip_section(section);
      else
        in_.fail(section, fmt::format("expected a section such as $Nodes or $Elements, found '{}'",
                                      section.text.substr(0, 40)));
    }
    return build();
  }

 private:
  void read_format() {
    in_.expect("$MeshFormat", "at the start of a Gmsh file");
    const Token v = in_.next("the format version (4.1 or 2.2)");
    if (v.text == "4.1")
      version_ = 4;
    else if (v.text == "2.2")
      version_ = 2;
    else
      in_.fail(v, fmt::format("Gmsh format version {} is not supported: expected 4.1 or 2.2 "
                              "(gmsh -format msh41 or msh22)",
                              v.text.substr(0, 20)));
    const Token binary = in_.next("the file type (0 for ASCII)");
    if (binary.text != "0")
      in_.fail(binary, "binary Gmsh files are not supported: save as ASCII (gmsh -bin 0)");
    in_.integer("the data size", 4, 16);
    in_.expect("$EndMeshFormat", "after the format line");
  }

  void read_physical_names() {
    const long long n = in_.integer("the number of physical names", 0, kMaxCount);
    in_.check_fits(n, 6, in_.last(), "physical names");
    for (long long i = 0; i < n; ++i) {
      const int dim = int(in_.integer("the dimension of a physical name", 0, 3));
      const int tag = int(in_.integer("a physical tag", 1, INT_MAX));
      Token name = in_.rest_of_line();
      std::string_view s = name.text;
      if (s.size() < 2 || s.front() != '"' || s.back() != '"')
        in_.fail(name, fmt::format("expected a physical name in double quotes, found '{}'",
                                   s.substr(0, 40)));
      names_[{dim, tag}] = std::string(s.substr(1, s.size() - 2));
    }
    in_.expect("$EndPhysicalNames", "after the physical names");
  }

  std::vector<int> physical_tags() {
    const long long n = in_.integer("the number of physical tags", 0, 1000);
    std::vector<int> tags;
    for (long long i = 0; i < n; ++i)
      tags.push_back(int(in_.integer("a physical tag", INT_MIN, INT_MAX)));
    return tags;
  }

  void read_entities() {
    long long counts[4];
    for (long long& c : counts) c = in_.integer("an entity count", 0, kMaxCount);
    for (int dim = 0; dim < 4; ++dim) {
      in_.check_fits(counts[dim], 8, in_.last(), "entities");
      for (long long e = 0; e < counts[dim]; ++e) {
        const int tag = int(in_.integer("an entity tag", INT_MIN, INT_MAX));
        for (int k = 0; k < (dim == 0 ? 3 : 6); ++k) in_.number("an entity bound");
        entity_physical_[{dim, tag}] = physical_tags();
        if (dim > 0) {
          const long long bounding = in_.integer("the number of bounding entities", 0, kMaxCount);
          in_.check_fits(bounding, 2, in_.last(), "bounding entities");
          for (long long b = 0; b < bounding; ++b)
            in_.integer("a bounding entity tag", LLONG_MIN, LLONG_MAX);
        }
      }
    }
    in_.expect("$EndEntities", "after the entities");
  }

  void add_node(long long tag, const Token& at) {
    if (!index_.emplace(tag, int(mesh_.points.size())).second)
      in_.fail(at, fmt::format("node tag {} appears twice", tag));
    point_at_.push_back(at);
    Vec3 p;
    for (int a = 0; a < 3; ++a)
      p[a] = in_.number(fmt::format("coordinate {} of node {}", "xyz"[a], tag)) / divisor_;
    mesh_.points.push_back(p);
  }

  void read_nodes_41() {
    const long long blocks = in_.integer("the number of node blocks", 0, kMaxCount);
    const long long total = in_.integer("the number of nodes", 0, kMaxCount);
    in_.check_fits(total, 8, in_.last(), "nodes");
    in_.integer("the smallest node tag", 0, LLONG_MAX);
    in_.integer("the largest node tag", 0, LLONG_MAX);
    for (long long b = 0; b < blocks; ++b) {
      const int dim = int(in_.integer("the entity dimension of a node block", 0, 3));
      in_.integer("the entity tag of a node block", INT_MIN, INT_MAX);
      const bool parametric = in_.integer("the parametric flag (0 or 1)", 0, 1) == 1;
      const long long n = in_.integer("the number of nodes in the block", 0, kMaxCount);
      if ((long long)mesh_.points.size() + n > total)
        in_.fail(in_.last(),
                 fmt::format("the node blocks hold more than the {} nodes announced", total));
      in_.check_fits(n, 8, in_.last(), "nodes");
      std::vector<std::pair<long long, Token>> tags;
      for (long long i = 0; i < n; ++i) {
        const long long tag = in_.integer("a node tag", 1, LLONG_MAX);
        tags.push_back({tag, in_.last()});
      }
      for (const auto& [tag, at] : tags) {
        add_node(tag, at);
        for (int k = 0; parametric && k < dim; ++k) in_.number("a parametric coordinate");
      }
    }
    if ((long long)mesh_.points.size() != total)
      in_.fail(in_.last(), fmt::format("$Nodes announced {} nodes, its blocks hold {}", total,
                                       mesh_.points.size()));
    in_.expect("$EndNodes", "after the nodes");
  }

  void read_nodes_22() {
    const long long n = in_.integer("the number of nodes", 0, kMaxCount);
    in_.check_fits(n, 8, in_.last(), "nodes");
    for (long long i = 0; i < n; ++i) {
      const long long tag = in_.integer("a node tag", 1, LLONG_MAX);
      add_node(tag, in_.last());
    }
    in_.expect("$EndNodes", "after the nodes");
  }

  const ElementType& element_type(long long code) {
    for (const ElementType& t : kTypes)
      if (t.code == code) return t;
    in_.fail(in_.last(),
             fmt::format("Gmsh element type {} is not supported: expected linear elements, 2 "
                         "(triangle), 3 (quad), 4 (tetrahedron), 5 (hexahedron), 6 (prism), or "
                         "1 (line) and 15 (point) for node sets (mesh with order 1)",
                         code));
  }

  void read_element_nodes(Element& e, long long tag) {
    for (int j = 0; j < e.type->nodes; ++j) {
      e.nodes[size_t(j)] = in_.integer(fmt::format("node {} of element {}", j, tag), 1, LLONG_MAX);
      if (!index_.contains(e.nodes[size_t(j)]))
        in_.fail(in_.last(), fmt::format("node {} of element {} is tag {}, which $Nodes does not "
                                         "define",
                                         j, tag, e.nodes[size_t(j)]));
    }
    elements_.push_back(std::move(e));
  }

  void read_elements_41() {
    if (mesh_.points.empty()) in_.fail(in_.last(), "$Elements before $Nodes");
    const long long blocks = in_.integer("the number of element blocks", 0, kMaxCount);
    const long long total = in_.integer("the number of elements", 0, kMaxCount);
    in_.check_fits(total, 4, in_.last(), "elements");
    in_.integer("the smallest element tag", 0, LLONG_MAX);
    in_.integer("the largest element tag", 0, LLONG_MAX);
    for (long long b = 0; b < blocks; ++b) {
      const int dim = int(in_.integer("the entity dimension of an element block", 0, 3));
      const int entity = int(in_.integer("the entity tag of an element block", INT_MIN, INT_MAX));
      const ElementType& type = element_type(in_.integer("the element type", LLONG_MIN, LLONG_MAX));
      if (type.dimension != dim)
        in_.fail(in_.last(), fmt::format("element type {} has dimension {}, its block says {}",
                                         type.code, type.dimension, dim));
      const long long n = in_.integer("the number of elements in the block", 0, kMaxCount);
      if ((long long)elements_.size() + n > total)
        in_.fail(in_.last(), fmt::format("the element blocks hold more than the {} elements "
                                         "announced",
                                         total));
      const auto physical = entity_physical_.find({dim, entity});
      for (long long i = 0; i < n; ++i) {
        Element e{&type, {}, {}, {}};
        const long long tag = in_.integer("an element tag", 1, LLONG_MAX);
        e.at = in_.last();
        if (physical != entity_physical_.end()) e.physical = physical->second;
        read_element_nodes(e, tag);
      }
    }
    if ((long long)elements_.size() != total)
      in_.fail(in_.last(), fmt::format("$Elements announced {} elements, its blocks hold {}", total,
                                       elements_.size()));
    in_.expect("$EndElements", "after the elements");
  }

  void read_elements_22() {
    if (mesh_.points.empty()) in_.fail(in_.last(), "$Elements before $Nodes");
    const long long n = in_.integer("the number of elements", 0, kMaxCount);
    in_.check_fits(n, 8, in_.last(), "elements");
    for (long long i = 0; i < n; ++i) {
      const long long tag = in_.integer("an element tag", 1, LLONG_MAX);
      Element e{nullptr, {}, {}, in_.last()};
      e.type = &element_type(in_.integer("the element type", LLONG_MIN, LLONG_MAX));
      const long long tags = in_.integer("the number of element tags", 0, 100);
      for (long long k = 0; k < tags; ++k) {
        const long long t = in_.integer("an element tag", LLONG_MIN, LLONG_MAX);
        if (k == 0 && t > 0 && t <= INT_MAX) e.physical.push_back(int(t));
      }
      read_element_nodes(e, tag);
    }
    in_.expect("$EndElements", "after the elements");
  }

  void skip_section(const Token& section) {
    const std::string end = "$End" + std::string(section.text.substr(1));
    while (true) {
      const Token t = in_.next(fmt::format("'{}' closing {}", end, section.text));
      if (t.text == end) return;
    }
  }

  Mesh build() {
    if (elements_.empty()) in_.fail_here("the file has no $Elements (or none in it)");
    int top = 0;
    for (const Element& e : elements_) top = std::max(top, e.type->dimension);
    if (top < 2)
      in_.fail(elements_.front().at,
               "the file has only points and lines: a mesh needs triangles, quads, tetrahedra, "
               "hexahedra or prisms");
    std::map<std::string, std::set<int>> sets;
    for (const Element& e : elements_) {
      Cell cell;
      for (int j = 0; j < e.type->nodes; ++j) cell.nodes[size_t(j)] = index_.at(e.nodes[size_t(j)]);
      for (int p : e.physical) {
        const auto named = names_.find({e.type->dimension, p});
        const std::string name =
            named != names_.end() ? named->second : fmt::format("physical_{}", p);
        sets[name].insert(cell.nodes.begin(), cell.nodes.begin() + e.type->nodes);
      }
      if (e.type->dimension != top) continue;
      cell.type = *e.type->cell;
      if (cell.type == CellType::wedge) {
        // A Gmsh prism's first triangle faces its second one; VTK's faces away from it.
        std::swap(cell.nodes[1], cell.nodes[2]);
        std::swap(cell.nodes[4], cell.nodes[5]);
      }
      mesh_.cells.push_back(cell);
    }
    for (auto& [name, nodes] : sets) mesh_.node_sets[name].assign(nodes.begin(), nodes.end());
    mesh_io::check_points_used(mesh_, point_at_, in_);
    return std::move(mesh_);
  }

  Lexer in_;
  double divisor_;
  int version_ = 4;
  Mesh mesh_;
  std::vector<Token> point_at_;
  std::unordered_map<long long, int> index_;  // node tag -> point
  std::map<std::pair<int, int>, std::string> names_;
  std::map<std::pair<int, int>, std::vector<int>> entity_physical_;
  std::vector<Element> elements_;
};

}  // namespace

Mesh parse_gmsh_mesh(std::string_view text, const std::string& name, double divisor) {
  mesh_io::check_text(text, name);
  return GmshReader(text, name, divisor).read();
}

}  // namespace phymul
