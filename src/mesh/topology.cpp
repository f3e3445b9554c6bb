// Mesh topology: edge adjacency, ordered one-rings, boundary surfaces and the measures that
// follow from them. Everything is built by counting and sorting flat arrays (no per-node
// containers), so it stays O(n log n) on meshes of a few hundred thousand cells.
#include <algorithm>
#include <cstdint>
#include <limits>
#include <sstream>

#include "mesh/cell_tables.hpp"
#include "phymul/mesh.hpp"

namespace phymul {

using namespace mesh_detail;

namespace {

void check_all_node_ranges(const Mesh& mesh) {
  for (std::size_t i = 0; i < mesh.cells.size(); ++i) {
    check_node_range(mesh.cells[i], std::ptrdiff_t(i), mesh.points.size());
  }
}

// Turns per-row counts (stored at offsets[row + 1]) into offsets.
void accumulate_offsets(std::vector<int>& offsets) {
  for (std::size_t i = 1; i < offsets.size(); ++i) offsets[i] += offsets[i - 1];
}

// Node -> incident cells, each item packed as cell * 8 + local position of the node.
Adjacency node_cells(const Mesh& mesh) {
  Adjacency incidence;
  incidence.offsets.assign(mesh.points.size() + 1, 0);
  for (const Cell& cell : mesh.cells) {
    for (int node : cell.node_span()) ++incidence.offsets[node + 1];
  }
  accumulate_offsets(incidence.offsets);
  incidence.indices.resize(incidence.offsets.back());
  std::vector<int> cursor(incidence.offsets.begin(), incidence.offsets.end() - 1);
  for (std::size_t c = 0; c < mesh.cells.size(); ++c) {
    const auto nodes = mesh.cells[c].node_span();
    for (std::size_t k = 0; k < nodes.size(); ++k) {
      incidence.indices[cursor[nodes[k]]++] = int(c) * 8 + int(k);
    }
  }
  return incidence;
}

// One cell's wedge of the fan around a node: from its next neighbour to its previous one,
// i.e. counter-clockwise around the node seen from the side the cell normal points to.
struct FanEdge {
  int from, to, cell;
};

// One end of a cell edge at the fan's centre node v: `outgoing` for v->neighbour.
struct EdgeEnd {
  int neighbour, cell;
  bool outgoing;
};

std::string node_prefix(int node) { return "node " + std::to_string(node) + ": "; }

void collect_fan(const Mesh& mesh, int node, std::span<const int> incident,
                 std::vector<FanEdge>& fan) {
  fan.clear();
  for (int packed : incident) {
    const int c = packed / 8, k = packed % 8;
    const auto nodes = mesh.cells[c].node_span();
    const int n = int(nodes.size());
    const int next = nodes[(k + 1) % n], prev = nodes[(k + n - 1) % n];
    if (next == node || prev == node) {
      throw MeshError(node_prefix(node) + describe_cell(mesh.cells[c], c) + " uses it twice");
    }
    fan.push_back({next, prev, c});
  }
}

std::string cell_list(std::span<const EdgeEnd> ends) {
  std::ostringstream out;
  for (std::size_t i = 0; i < ends.size(); ++i) out << (i ? ", " : "") << ends[i].cell;
  return out.str();
}

// Every edge at the node must be used by one cell (border) or by two cells in opposite
// directions; returns the number of border edges.
int check_edge_use(int node, const std::vector<FanEdge>& fan, std::vector<EdgeEnd>& ends) {
  ends.clear();
  for (const FanEdge& f : fan) {
    ends.push_back({f.from, f.cell, true});
    ends.push_back({f.to, f.cell, false});
  }
  std::sort(ends.begin(), ends.end(),
            [](const EdgeEnd& a, const EdgeEnd& b) { return a.neighbour < b.neighbour; });
  int borders = 0;
  for (std::size_t i = 0; i < ends.size();) {
    std::size_t j = i;
    while (j < ends.size() && ends[j].neighbour == ends[i].neighbour) ++j;
    const std::span<const EdgeEnd> group(ends.data() + i, j - i);
    const std::string edge =
        "edge " + std::to_string(node) + "-" + std::to_string(ends[i].neighbour);
    if (group.size() > 2) {
      throw MeshError(node_prefix(node) + "the surface is non-manifold: " + edge +
                      " is shared by " + std::to_string(group.size()) + " cells (" +
                      cell_list(group) + ")");
    }
    if (group.size() == 2 && group[0].outgoing == group[1].outgoing) {
      throw MeshError(node_prefix(node) + "the surface is inconsistently oriented: cells " +
                      cell_list(group) + " both run along " + edge +
                      " in the same direction (flip one of them)");
    }
    borders += group.size() == 1 ? 1 : 0;
    i = j;
  }
  return borders;
}

// Walks the fan edges from `start` and appends the visited neighbours to `ring`: all of
// them for an open fan, the start only once for a cycle. The fan edges are sorted by
// `from`, each `from` unique (check_edge_use guarantees it).
void walk_fan(int node, const std::vector<FanEdge>& fan, int start, bool cycle,
              std::vector<int>& ring) {
  int current = start;
  std::size_t steps = 0;
  ring.push_back(current);
  while (steps < fan.size()) {
    const auto it = std::lower_bound(fan.begin(), fan.end(), current,
                                     [](const FanEdge& f, int v) { return f.from < v; });
    if (it == fan.end() || it->from != current) break;  // reached the other border
    current = it->to;
    ++steps;
    if (current == start) break;
    ring.push_back(current);
  }
  if (steps != fan.size() || (cycle && current != start)) {
    throw MeshError(node_prefix(node) +
                    "the surface is non-manifold: the cells around it form more than one fan "
                    "(they touch only at this node)");
  }
}

// The start of an open fan: the neighbour that no fan edge leads to.
int fan_start(const std::vector<FanEdge>& fan, std::vector<int>& scratch) {
  scratch.clear();
  for (const FanEdge& f : fan) scratch.push_back(f.to);
  std::sort(scratch.begin(), scratch.end());
  for (const FanEdge& f : fan) {
    if (!std::binary_search(scratch.begin(), scratch.end(), f.from)) return f.from;
  }
  return fan.front().from;  // unreachable for an open fan
}

constexpr int kMaxFacesPerCell = 6;
constexpr int kNoNode = std::numeric_limits<int>::max();

// A cell face keyed by its sorted node ids, so that the copies from two cells meet.
struct FaceRecord {
  std::array<int, 4> key;
  int cell, face;
};

FaceRecord face_record(const Cell& cell, int c, int f) {
  const LocalFace& face = cell_faces(cell.type)[f];
  std::array<int, 4> key = face_nodes(cell, face);
  if (face.size == 3) key[3] = kNoNode;  // sorts last
  std::sort(key.begin(), key.end());
  return {key, c, f};
}

// All cell faces, grouped so that equal keys are adjacent: bucketed by their smallest node
// (a counting sort), then each short bucket sorted by key.
std::vector<FaceRecord> grouped_face_records(const Mesh& mesh) {
  std::vector<int> offsets(mesh.points.size() + 1, 0);
  for (const Cell& cell : mesh.cells) {
    for (const LocalFace& face : cell_faces(cell.type)) {
      const auto ids = face_nodes(cell, face);
      ++offsets[*std::min_element(ids.begin(), ids.begin() + face.size) + 1];
    }
  }
  accumulate_offsets(offsets);
  std::vector<FaceRecord> records(offsets.back());
  std::vector<int> cursor(offsets.begin(), offsets.end() - 1);
  for (std::size_t c = 0; c < mesh.cells.size(); ++c) {
    const int faces = int(cell_faces(mesh.cells[c].type).size());
    for (int f = 0; f < faces; ++f) {
      const FaceRecord record = face_record(mesh.cells[c], int(c), f);
      records[cursor[record.key[0]]++] = record;
    }
  }
  const auto by_key = [](const FaceRecord& a, const FaceRecord& b) { return a.key < b.key; };
  for (std::size_t node = 0; node < mesh.points.size(); ++node) {
    std::sort(records.begin() + offsets[node], records.begin() + offsets[node + 1], by_key);
  }
  return records;
}

std::string face_sharing_message(std::span<const FaceRecord> group) {
  std::ostringstream out;
  out << "face (nodes";
  for (int node : group[0].key) {
    if (node != kNoNode) out << ' ' << node;
  }
  out << ") is shared by " << group.size() << " cells (";
  for (std::size_t i = 0; i < group.size(); ++i) out << (i ? ", " : "") << group[i].cell;
  out << "); a volume mesh face may belong to at most two cells";
  return out.str();
}

// Flags, per cell * kMaxFacesPerCell + local face, the faces used by exactly one cell.
std::vector<char> boundary_face_flags(const Mesh& mesh) {
  const std::vector<FaceRecord> records = grouped_face_records(mesh);
  std::vector<char> flags(mesh.cells.size() * kMaxFacesPerCell, 0);
  for (std::size_t i = 0; i < records.size();) {
    std::size_t j = i;
    while (j < records.size() && records[j].key == records[i].key) ++j;
    if (j - i > 2) throw MeshError(face_sharing_message({records.data() + i, j - i}));
    if (j - i == 1) flags[std::size_t(records[i].cell) * kMaxFacesPerCell + records[i].face] = 1;
    i = j;
  }
  return flags;
}

void append_polygon(const std::array<int, 4>& ids, int size, std::vector<Triangle>& out) {
  if (size == 3) {
    out.push_back({ids[0], ids[1], ids[2]});
    return;
  }
  for (const Triangle& t : split_quad(ids)) out.push_back(t);
}

std::vector<Triangle> volume_boundary(const Mesh& mesh) {
  const std::vector<char> flags = boundary_face_flags(mesh);
  std::vector<Triangle> triangles;
  for (std::size_t c = 0; c < mesh.cells.size(); ++c) {
    const Cell& cell = mesh.cells[c];
    const auto faces = cell_faces(cell.type);
    for (std::size_t f = 0; f < faces.size(); ++f) {
      if (flags[c * kMaxFacesPerCell + f]) {
        append_polygon(face_nodes(cell, faces[f]), faces[f].size, triangles);
      }
    }
  }
  return triangles;
}

std::vector<Triangle> surface_triangles(const Mesh& mesh) {
  std::vector<Triangle> triangles;
  triangles.reserve(mesh.cells.size() * 2);
  for (const Cell& cell : mesh.cells) {
    const auto& n = cell.nodes;
    append_polygon({n[0], n[1], n[2], cell.type == CellType::quad ? n[3] : -1},
                   node_count(cell.type), triangles);
  }
  return triangles;
}

}  // namespace

Adjacency edge_neighbours(const Mesh& mesh) {
  check_all_node_ranges(mesh);
  // Bucket both ends of every cell edge by node (duplicates included), then sort and
  // deduplicate each short row in place.
  Adjacency result;
  std::vector<int> bucket_offsets(mesh.points.size() + 1, 0);
  for (const Cell& cell : mesh.cells) {
    for (const LocalEdge& e : cell_edges(cell.type)) {
      ++bucket_offsets[cell.nodes[e[0]] + 1];
      ++bucket_offsets[cell.nodes[e[1]] + 1];
    }
  }
  accumulate_offsets(bucket_offsets);
  std::vector<int> items(bucket_offsets.back());
  std::vector<int> cursor(bucket_offsets.begin(), bucket_offsets.end() - 1);
  for (const Cell& cell : mesh.cells) {
    for (const LocalEdge& e : cell_edges(cell.type)) {
      const int a = cell.nodes[e[0]], b = cell.nodes[e[1]];
      items[cursor[a]++] = b;
      items[cursor[b]++] = a;
    }
  }
  result.offsets.assign(mesh.points.size() + 1, 0);
  int write = 0;
  for (std::size_t node = 0; node < mesh.points.size(); ++node) {
    const auto first = items.begin() + bucket_offsets[node];
    const auto last = items.begin() + bucket_offsets[node + 1];
    std::sort(first, last);
    const auto end = std::unique(first, last);
    write = int(std::copy(first, end, items.begin() + write) - items.begin());
    result.offsets[node + 1] = write;
  }
  items.resize(write);
  result.indices = std::move(items);
  return result;
}

Adjacency ordered_one_rings(const Mesh& mesh) {
  if (mesh.volumetric()) {
    throw MeshError("ordered_one_rings needs a surface mesh (triangles and quads), but cell 0 is " +
                    std::string(cell_type_name(mesh.cells.front().type)));
  }
  check_all_node_ranges(mesh);
  const Adjacency incidence = node_cells(mesh);
  Adjacency rings;
  rings.offsets.reserve(mesh.points.size() + 1);
  std::vector<FanEdge> fan;
  std::vector<EdgeEnd> ends;
  std::vector<int> scratch;
  for (int node = 0; node < int(mesh.points.size()); ++node) {
    collect_fan(mesh, node, incidence.row(node), fan);
    if (!fan.empty()) {
      const int borders = check_edge_use(node, fan, ends);
      std::sort(fan.begin(), fan.end(),
                [](const FanEdge& a, const FanEdge& b) { return a.from < b.from; });
      if (borders > 2) {
        throw MeshError(node_prefix(node) +
                        "the surface is non-manifold: " + std::to_string(borders) +
                        " border edges meet here (cells touching only at this node)");
      }
      const bool cycle = borders == 0;
      walk_fan(node, fan, cycle ? fan.front().from : fan_start(fan, scratch), cycle, rings.indices);
    }
    rings.offsets.push_back(int(rings.indices.size()));
  }
  return rings;
}

std::vector<Triangle> boundary_triangles(const Mesh& mesh) {
  check_all_node_ranges(mesh);
  return mesh.volumetric() ? volume_boundary(mesh) : surface_triangles(mesh);
}

bool is_closed(std::span<const Triangle> triangles) {
  if (triangles.empty()) return false;
  // Key: undirected edge (low, high) with the direction in the lowest bit, so a closed
  // surface sorts into pairs (key, key + 1).
  std::vector<std::uint64_t> keys;
  keys.reserve(triangles.size() * 3);
  for (const Triangle& t : triangles) {
    for (int k = 0; k < 3; ++k) {
      const int a = t[k], b = t[(k + 1) % 3];
      if (a < 0 || b < 0 || a == b) return false;
      const auto low = std::uint64_t(std::min(a, b)), high = std::uint64_t(std::max(a, b));
      keys.push_back(low << 33 | high << 1 | (a < b ? 0u : 1u));
    }
  }
  std::sort(keys.begin(), keys.end());
  if (keys.size() % 2 != 0) return false;
  for (std::size_t i = 0; i < keys.size(); i += 2) {
    if ((keys[i] & 1u) != 0 || keys[i + 1] != keys[i] + 1) return false;
  }
  return true;
}

double enclosed_volume(std::span<const Vec3> points, std::span<const Triangle> triangles) {
  double sum = 0.0;
  for (const Triangle& t : triangles) {
    sum += points[t[0]].dot(points[t[1]].cross(points[t[2]]));
  }
  return sum / 6.0;
}

std::vector<double> lumped_measure(const Mesh& mesh) {
  check_all_node_ranges(mesh);
  std::vector<double> lumped(mesh.points.size(), 0.0);
  for (const Cell& cell : mesh.cells) {
    const auto nodes = cell.node_span();
    const double share = cell_measure(mesh.points, cell) / double(nodes.size());
    for (int node : nodes) lumped[node] += share;
  }
  return lumped;
}

}  // namespace phymul
