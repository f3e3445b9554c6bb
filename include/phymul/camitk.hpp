// CamiTK exchange (docs/camitk.md): PML physical models (atoms, exclusive and informative
// components, cells) and LML loads (translations, forces, pressures with value events), read
// into plain structures and written back from a scene. Every problem is a MeshFileError naming
// the file, the line and column, the element and what was expected.
#pragma once

#include <array>
#include <filesystem>
#include <string>
#include <string_view>
#include <vector>

#include "phymul/mesh.hpp"
#include "phymul/mesh_io.hpp"
#include "phymul/scene.hpp"

namespace phymul {

// A component of a PML (a structuralComponent, or a multiComponent holding them), flattened:
// its cells and the atoms it names, as positions in PmlModel::atoms.
struct PmlComponent {
  std::string name;
  bool exclusive = true;    // under <exclusiveComponents>, else <informativeComponents>
  bool multi = false;       // a multiComponent: the union of the components below it
  std::vector<Cell> cells;  // TETRAHEDRON, HEXAHEDRON, WEDGE, TRIANGLE, QUAD, oriented as VTK's
  std::vector<int> atoms;   // every atom of its cells and atomRefs, sorted, unique
  std::vector<std::string> other_cells;  // types it holds that make no cell (LINE, POLY_VERTEX)
  int line = 0, column = 0;              // of its element
};

struct PmlModel {
  std::string name;
  std::vector<int> atom_ids;             // the atoms' `index`, in file order (sparse, unique)
  std::vector<Vec3> atoms;               // coordinates divided by the reader's divisor
  std::vector<PmlComponent> components;  // structural and multi components, in file order
  std::vector<std::string> notes;        // what the reader noticed (counts, reordered cells)

  const PmlComponent* find(std::string_view component) const;  // nullptr when absent
};

// Coordinates are divided by `divisor` (1000 for a file in millimetres). Cells are oriented
// as VTK's (a hexahedron listed inside out, as CamiTK allows, is reordered, with a note);
// the header's and nrOfStructures' counts are hints in CamiTK, so a wrong one is a note.
PmlModel parse_pml(std::string_view text, const std::string& name, double divisor = 1.0);
PmlModel read_pml(const std::filesystem::path& path, double divisor = 1.0);

// The object of one component: its cells and only the atoms they use (renumbered in file
// order; `atom_ids` gets each node's atom index), every informative component as a node set
// of the atoms it shares with it (named by pml_node_set_name). An empty `component` takes the
// only exclusive structural component with cells.
Mesh pml_object_mesh(const PmlModel& pml, const std::string& component, std::vector<int>* atom_ids,
                     const std::string& file_name);

// A component's name as a node set's: letters, digits, '_' and '-', '_' for the rest.
std::string pml_node_set_name(std::string_view component);

// An LML load, in SI: value(t) * direction is the translation (m), the force on each atom
// (N) or the pressure (Pa, along the faces' normals, direction unused).
struct LmlLoad {
  enum class Type { translation, force, pressure };
  // Per axis: free (not given), null (held at 0: "NULL") or given (value * component).
  enum class Axis { free, null, given };
  Type type = Type::force;
  std::vector<int> atoms;             // atom indices of <appliedTo> ("0-3,7")
  std::vector<std::string> names;     // or component names ("*": every atom)
  std::vector<double> dates, values;  // s; SI, sorted by date
  std::array<Axis, 3> axes{Axis::free, Axis::free, Axis::free};
  Vec3 direction = Vec3::Zero();
  std::string unit;  // as written ("mm"); the defaults: mm, N, kPa
  int line = 0;
};

std::vector<LmlLoad> parse_lml(std::string_view text, const std::string& name);
std::vector<LmlLoad> read_lml(const std::filesystem::path& path);

// `phymul export-pml`: the scene's objects as DIR/<stem>.pml (one exclusive component per
// object, node sets as informative components) and its loads, fixed and prescribed nodes as
// DIR/<stem>.lml, coordinates and translations in millimetres. Returns what LML cannot say
// (springs, obstacles, motions...), one sentence each. The scene must be prepared.
struct PmlExport {
  std::filesystem::path pml, lml;
  std::vector<std::string> notes;
};
PmlExport export_pml(const Scene& scene, const std::filesystem::path& dir);

}  // namespace phymul
