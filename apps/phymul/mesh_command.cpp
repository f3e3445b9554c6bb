#include <fmt/format.h>

#include <iostream>
#include <memory>

#include "commands.hpp"
#include "phymul/mesh_io.hpp"
#include "phymul/meshing.hpp"
#include "phymul/schema.hpp"
#include "phymul/vtk.hpp"

namespace phymul::cli {
namespace {

struct Settings {
  std::string surface, output, edge, remesh, units = "m";
};

double divisor_of(const std::string& units) {
  if (units == "mm") return 1000.0;
  if (units == "cm") return 100.0;
  if (units == "um") return 1e6;
  return 1.0;
}

std::string quality_text(const Remeshed& r) {
  const SurfaceQuality& q = r.quality;
  return fmt::format(
      "remeshed: {} triangles, {} points; edges {:.3g}/{:.3g}/{:.3g} mm (min/mean/max), "
      "smallest angle {:.1f} degrees, largest aspect ratio {:.2f}; at most {:.3g} mm from the "
      "input surface; enclosed volume {:.4g} mL -> {:.4g} mL ({:+.2f}%)",
      q.triangles, r.surface.points.size(), q.edge_min * 1e3, q.edge_mean * 1e3, q.edge_max * 1e3,
      q.min_angle_deg, q.max_aspect, r.deviation * 1e3, r.volume_before * 1e6, r.volume_after * 1e6,
      100.0 * (r.volume_after - r.volume_before) / r.volume_before);
}

// The surface, remeshed when asked; its report printed.
Mesh surface_to_fill(const Settings& s, Mesh surface) {
  if (s.remesh.empty()) return surface;
  const Remeshed r = remesh_surface(surface, parse_scene_field("mesh", "remesh", s.remesh));
  std::cout << quality_text(r) << '\n';
  return r.surface;
}

int mesh(const Settings& s) {
  try {
    if (s.edge.empty() && s.remesh.empty())
      throw std::invalid_argument("give --edge (fill with tetrahedra), --remesh, or both");
    const double divisor = divisor_of(s.units);
    std::vector<std::string> notes;
    const Mesh read = read_mesh_file(s.surface, divisor, &notes);
    if (read.volumetric()) throw MeshError(fmt::format("{} is already a volume mesh", s.surface));
    for (const std::string& note : notes) std::cout << note << '\n';
    const Mesh surface = surface_to_fill(s, read);
    if (s.edge.empty()) {  // --remesh alone: the remeshed surface is the output
      Mesh out = surface;
      for (Vec3& p : out.points) p *= divisor;  // back in the surface file's units
      write_vtu(s.output, out.points, out.cells, {}, {}, VtuEncoding::ascii);
      std::cout << fmt::format("{}: {} triangles, coordinates in {}\n", s.output, out.cells.size(),
                               s.units);
      return 0;
    }
    const double edge = parse_scene_field("mesh", "edge", s.edge);  // a length, with its unit
    Mesh volume = fill_with_tetrahedra(surface, edge);
    const TetraQuality q = tetra_quality(volume);
    for (Vec3& p : volume.points) p *= divisor;  // back in the surface file's units
    write_vtu(s.output, volume.points, volume.cells, {}, {}, VtuEncoding::ascii);
    std::cout << fmt::format(
        "{}: {} tetrahedra, {} points ({} on the surface), coordinates in {}; smallest dihedral "
        "angle {:.1f} degrees, largest radius-edge ratio {:.2f}\n",
        s.output, q.tetrahedra, volume.points.size(), surface.points.size(), s.units,
        q.min_dihedral_deg, q.max_radius_edge);
    return 0;
  } catch (const std::exception& e) {  // a bad file, surface or edge: said, exit 1
    std::cerr << "error: " << e.what() << '\n';
    return 1;
  }
}

}  // namespace

Command add_mesh_command(CLI::App& parent) {
  auto settings = std::make_shared<Settings>();
  CLI::App* app = parent.add_subcommand(
      "mesh",
      "fill a closed surface (STL, OBJ, PLY, VTP) with tetrahedra, or remesh it, written as .vtu");
  app->add_option("surface", settings->surface, "closed surface file (.stl, .obj, .ply, .vtp)")
      ->required()
      ->check(CLI::ExistingFile);
  app->add_option("-o,--output", settings->output, "volume mesh to write (.vtu)")->required();
  app->add_option("--edge", settings->edge,
                  "largest edge of the tetrahedra inside, with its unit ('4 mm')");
  app->add_option("--remesh", settings->remesh,
                  "remesh the surface to this edge first ('8 mm'); without --edge, the remeshed "
                  "surface is the output");
  app->add_option("--units", settings->units, "length unit of the surface file's coordinates")
      ->check(CLI::IsMember({"m", "cm", "mm", "um"}));
  return {app, [settings] { return mesh(*settings); }};
}

}  // namespace phymul::cli
