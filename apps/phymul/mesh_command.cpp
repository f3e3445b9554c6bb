#include <fmt/format.h>
#include <fmt/ranges.h>

#include <iostream>
#include <memory>

#include "commands.hpp"
#include "phymul/label_surface.hpp"
#include "phymul/mesh_io.hpp"
#include "phymul/meshing.hpp"
#include "phymul/nifti.hpp"
#include "phymul/schema.hpp"
#include "phymul/vtk.hpp"

namespace phymul::cli {
namespace {

struct Settings {
  std::string input, output, edge, remesh, units;
  std::vector<int> labels;
  bool surface_only = false;
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
Mesh remeshed(const Settings& s, Mesh surface) {
  if (s.remesh.empty()) return surface;
  const Remeshed r = remesh_surface(surface, parse_scene_field("mesh", "remesh", s.remesh));
  std::cout << quality_text(r) << '\n';
  return r.surface;
}

double tetra_volume(const Mesh& volume) {
  double sum = 0.0;
  for (const Cell& c : volume.cells) sum += cell_measure(volume.points, c);
  return sum;
}

std::string percent(double value, double reference) {
  return fmt::format("{:+.2f} %", 100.0 * (value - reference) / reference);
}

// A label image's surface, and what it says about the image (m^3 as mL).
Mesh image_surface(const Settings& s, double edge, const std::string& units) {
  std::vector<std::string> notes;
  const LabelImage image = read_nifti_labels(s.input, &notes);
  LabelSurfaceReport r;
  Mesh surface, volume;
  if (s.surface_only)
    surface = label_surface(image, s.labels, edge, &r);
  else
    volume = label_volume(image, s.labels, edge, &r, &surface);
  for (const std::string& note : notes) std::cout << note << '\n';
  const Vec3 voxel = image.spacing() * 1e3, c = r.centroid * 1e3;
  const Vec3 lo = r.box[0] * 1e3, hi = r.box[1] * 1e3;
  std::cout << fmt::format(
      "{}: labels {}: {} voxels of {:.3g} x {:.3g} x {:.3g} mm, {:.2f} mL; slices across axis {}\n"
      "surface: {} triangles, {} points (grid {:.3g} mm), encloses {:.2f} mL ({} against the "
      "voxels); centroid ({:.2f}, {:.2f}, {:.2f}) mm, box ({:.1f}, {:.1f}, {:.1f}) to ({:.1f}, "
      "{:.1f}, {:.1f}) mm in the image's physical frame\n",
      s.input, fmt::join(s.labels, ", "), r.voxels, voxel[0], voxel[1], voxel[2],
      r.labelled_volume * 1e6, "ijk"[r.slice_axis], surface.cells.size(), surface.points.size(),
      r.grid_spacing * 1e3, r.surface_volume * 1e6, percent(r.surface_volume, r.labelled_volume),
      c[0], c[1], c[2], lo[0], lo[1], lo[2], hi[0], hi[1], hi[2]);
  if (r.dropped_components > 0)
    std::cout << fmt::format("left out: {} smaller parts (islands or cavities), {:.3f} mL\n",
                             r.dropped_components, r.dropped_volume * 1e6);
  if (r.cleanup_stage > 0)
    std::cout << fmt::format("the surface is {} (coarsened and smoothed, it folded)\n",
                             r.cleanup_stage == 1 ? "smoothed only" : "as cut from the grid");
  if (!s.surface_only) {
    const TetraQuality q = tetra_quality(volume);
    const double v = tetra_volume(volume);
    std::cout << fmt::format(
        "{}: {} tetrahedra, {} points ({} on the surface), coordinates in {}; volume {:.2f} mL "
        "({} against the surface, {} against the voxels); smallest dihedral angle {:.1f} "
        "degrees, largest radius-edge ratio {:.2f}\n",
        s.output, q.tetrahedra, volume.points.size(), surface.points.size(), units, v * 1e6,
        percent(v, r.surface_volume), percent(v, r.labelled_volume), q.min_dihedral_deg,
        q.max_radius_edge);
    return volume;
  }
  std::cout << fmt::format("{}: the surface, coordinates in {}\n", s.output, units);
  return surface;
}

// A surface file's surface, remeshed when asked, filled when an edge is given (edge > 0).
Mesh file_surface_volume(const Settings& s, double edge, double divisor) {
  std::vector<std::string> notes;
  const Mesh read = read_mesh_file(s.input, divisor, &notes);
  if (read.volumetric()) throw MeshError(fmt::format("{} is already a volume mesh", s.input));
  for (const std::string& note : notes) std::cout << note << '\n';
  const Mesh surface = remeshed(s, read);
  if (s.surface_only || edge == 0.0) {
    std::cout << fmt::format("{}: {} triangles, the surface, coordinates in {}\n", s.output,
                             surface.cells.size(), s.units.empty() ? "m" : s.units);
    return surface;
  }
  Mesh volume = fill_with_tetrahedra(surface, edge);
  const TetraQuality q = tetra_quality(volume);
  std::cout << fmt::format(
      "{}: {} tetrahedra, {} points ({} on the surface), coordinates in {}; smallest dihedral "
      "angle {:.1f} degrees, largest radius-edge ratio {:.2f}\n",
      s.output, q.tetrahedra, volume.points.size(), surface.points.size(),
      s.units.empty() ? "m" : s.units, q.min_dihedral_deg, q.max_radius_edge);
  return volume;
}

int mesh(const Settings& s) {
  try {
    const bool image = is_nifti_path(s.input);
    // A surface file's coordinates are in --units (m); an image's frame is written in mm.
    const std::string units = !s.units.empty() ? s.units : image ? "mm" : "m";
    const double divisor = divisor_of(units);
    if (s.edge.empty() && (image || s.remesh.empty()))
      throw std::invalid_argument(image ? "give --edge: the surface's and the tetrahedra's size"
                                        : "give --edge (fill with tetrahedra), --remesh, or both");
    if (image && !s.remesh.empty())
      throw std::invalid_argument(
          "--remesh applies to surface files; an image's surface is made "
          "at --edge");
    // A length, with its unit; 0: no filling (--remesh alone writes the remeshed surface).
    const double edge = s.edge.empty() ? 0.0 : parse_scene_field("mesh", "edge", s.edge);
    if (image && s.labels.empty())
      throw MeshError(
          fmt::format("{} is a label image: say which labels make the object "
                      "(--labels 1,2)",
                      s.input));
    if (!image && !s.labels.empty())
      throw MeshError("--labels applies to label images (.nii, .nii.gz) only");
    Mesh out = image ? image_surface(s, edge, units) : file_surface_volume(s, edge, divisor);
    for (Vec3& p : out.points) p *= divisor;  // metres inside, the asked unit outside
    write_vtu(s.output, out.points, out.cells, {}, {}, VtuEncoding::ascii);
    return 0;
  } catch (const std::exception& e) {  // a bad file, image, surface or edge: said, exit 1
    std::cerr << "error: " << e.what() << '\n';
    return 1;
  }
}

}  // namespace

Command add_mesh_command(CLI::App& parent) {
  auto settings = std::make_shared<Settings>();
  CLI::App* app = parent.add_subcommand(
      "mesh",
      "fill a closed surface (STL, OBJ, PLY, VTP) or a label image's labels (NIfTI) with "
      "tetrahedra, or remesh a surface, written as .vtu");
  app->add_option("input", settings->input,
                  "closed surface file (.stl, .obj, .ply, .vtp) or label image (.nii, .nii.gz)")
      ->required()
      ->check(CLI::ExistingFile);
  app->add_option("-o,--output", settings->output, "volume mesh to write (.vtu)")->required();
  app->add_option("--edge", settings->edge,
                  "largest edge of the tetrahedra inside, with its unit ('4 mm'); for an image "
                  "also the surface triangles' size");
  app->add_option("--remesh", settings->remesh,
                  "surface file: remesh it to this edge first ('8 mm'); without --edge, the "
                  "remeshed surface is the output");
  app->add_option("--labels", settings->labels,
                  "label image: the labels that make the object, e.g. 1,2 (required there)")
      ->delimiter(',');
  app->add_flag("--surface-only", settings->surface_only,
                "write the closed surface (triangles) instead of filling it");
  app->add_option("--units", settings->units,
                  "length unit of the surface file's coordinates and of those written (default: "
                  "m for surfaces, mm for images)")
      ->check(CLI::IsMember({"m", "cm", "mm", "um"}));
  return {app, [settings] { return mesh(*settings); }};
}

}  // namespace phymul::cli
