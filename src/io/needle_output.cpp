#include "io/needle_output.hpp"

#include <fmt/format.h>

#include <ostream>

#include "constraints/needle.hpp"
#include "phymul/vtk.hpp"

namespace phymul {
namespace {

struct NeedleGeometry {
  std::vector<Vec3> points;
  std::vector<std::array<int, 2>> cells;  // a line (two points) or a vertex (second -1)
  std::vector<int> needle, kind;
};

NeedleGeometry needle_geometry(const Model& model, const Data& data) {
  NeedleGeometry g;
  for (size_t k = 0; k < model.needles.size(); ++k) {
    const Needle& n = model.needles[k];
    const NeedleState& s = data.needles[k];
    auto add = [&](const Vec3& p, int kind, bool line) {
      g.points.push_back(p);
      const int i = int(g.points.size()) - 1;
      if (line)
        g.cells.back()[1] = i;
      else
        g.cells.push_back({i, -1}), g.needle.push_back(int(k)), g.kind.push_back(kind);
    };
    add(n.base, 0, false);
    add(needle_tip(n, s.depth), 0, true);
    for (const TrackPoint& p : s.track) add(p.point.at(data.x), 1, false);
    if (n.target_component >= 0) add(n.target.at(data.x), 2, false);
  }
  return g;
}

void write_ints(std::ostream& o, const char* type, const char* name, const std::vector<int>& v) {
  o << fmt::format("        <DataArray type=\"{}\" Name=\"{}\" format=\"ascii\">\n         ", type,
                   name);
  for (int x : v) o << ' ' << x;
  o << "\n        </DataArray>\n";
}

}  // namespace

void write_needle_frame(const std::filesystem::path& path, const Model& model, const Data& data) {
  const NeedleGeometry g = needle_geometry(model, data);
  std::vector<int> connectivity, offsets, types;
  for (const auto& c : g.cells) {
    connectivity.push_back(c[0]);
    if (c[1] >= 0) connectivity.push_back(c[1]);
    offsets.push_back(int(connectivity.size()));
    types.push_back(c[1] >= 0 ? 3 : 1);  // VTK_LINE, VTK_VERTEX
  }
  write_file_atomically(path, [&](std::ostream& o) {
    o << "<?xml version=\"1.0\"?>\n<VTKFile type=\"UnstructuredGrid\" version=\"1.0\" "
         "byte_order=\"LittleEndian\">\n  <UnstructuredGrid>\n";
    o << fmt::format("    <Piece NumberOfPoints=\"{}\" NumberOfCells=\"{}\">\n", g.points.size(),
                     g.cells.size());
    o << "      <Points>\n        <DataArray type=\"Float64\" NumberOfComponents=\"3\" "
         "format=\"ascii\">\n";
    for (const Vec3& p : g.points) o << fmt::format("          {} {} {}\n", p.x(), p.y(), p.z());
    o << "        </DataArray>\n      </Points>\n      <Cells>\n";
    write_ints(o, "Int32", "connectivity", connectivity);
    write_ints(o, "Int32", "offsets", offsets);
    write_ints(o, "UInt8", "types", types);
    o << "      </Cells>\n      <CellData>\n";
    write_ints(o, "Int32", "needle", g.needle);
    write_ints(o, "Int32", "kind", g.kind);
    o << "      </CellData>\n    </Piece>\n  </UnstructuredGrid>\n</VTKFile>\n";
  });
}

std::string needle_monitor_header(const Model& model) {
  std::string h;
  for (const Needle& n : model.needles) {
    const std::string p = ",needle_" + n.name + "_";
    h += p + "depth_m" + p + "axial_force_N" + p + "lateral_force_N";
    if (n.target_component >= 0) h += p + "target_distance_m" + p + "target_displacement_m";
  }
  return h;
}

std::string needle_monitor_row(const Model& model, const Data& data) {
  std::string row;
  for (size_t k = 0; k < model.needles.size(); ++k) {
    const Needle& n = model.needles[k];
    const NeedleState& s = data.needles[k];
    row += fmt::format(",{},{},{}", s.depth, needle_axial_force(n, s), needle_lateral_force(n, s));
    if (n.target_component < 0) continue;
    const Vec3 target = n.target.at(data.x);
    row += fmt::format(",{},{}", (target - needle_tip(n, s.depth)).norm(),
                       (target - n.target.at(model.rest_position)).norm());
  }
  return row;
}

std::vector<NeedlePuncture> needle_punctures(const Model& model, const Data& data) {
  std::vector<NeedlePuncture> out;
  for (size_t k = 0; k < model.needles.size(); ++k)
    for (const PunctureEvent& e : data.needles[k].punctures) {
      const Needle& n = model.needles[k];
      const int c = n.tissues[size_t(e.tissue)].component;
      out.push_back({n.name, model.components[size_t(c)].name, e.time, e.depth, e.force});
    }
  return out;
}

}  // namespace phymul
