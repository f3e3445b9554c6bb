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
  std::string surface, output, edge, units = "m";
};

double divisor_of(const std::string& units) {
  if (units == "mm") return 1000.0;
  if (units == "cm") return 100.0;
  if (units == "um") return 1e6;
  return 1.0;
}

int mesh(const Settings& s) {
  try {
    const double divisor = divisor_of(s.units);
    const double edge = parse_scene_field("mesh", "edge", s.edge);  // a length, with its unit
    std::vector<std::string> notes;
    const Mesh surface = read_mesh_file(s.surface, divisor, &notes);
    if (surface.volumetric())
      throw MeshError(fmt::format("{} is already a volume mesh", s.surface));
    Mesh volume = fill_with_tetrahedra(surface, edge);
    const TetraQuality q = tetra_quality(volume);
    for (Vec3& p : volume.points) p *= divisor;  // back in the surface file's units
    write_vtu(s.output, volume.points, volume.cells, {}, {}, VtuEncoding::ascii);
    for (const std::string& note : notes) std::cout << note << '\n';
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
      "mesh", "fill a closed surface (STL, OBJ, PLY, VTP) with tetrahedra, written as .vtu");
  app->add_option("surface", settings->surface, "closed surface file (.stl, .obj, .ply, .vtp)")
      ->required()
      ->check(CLI::ExistingFile);
  app->add_option("-o,--output", settings->output, "volume mesh to write (.vtu)")->required();
  app->add_option("--edge", settings->edge,
                  "largest edge of the tetrahedra inside, with its unit ('4 mm')")
      ->required();
  app->add_option("--units", settings->units, "length unit of the surface file's coordinates")
      ->check(CLI::IsMember({"m", "cm", "mm", "um"}));
  return {app, [settings] { return mesh(*settings); }};
}

}  // namespace phymul::cli
