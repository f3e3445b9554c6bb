#include <fmt/format.h>

#include <sstream>

#include "phymul/studies/truthcube.hpp"
#include "phymul/vtk.hpp"

namespace phymul::truthcube {
namespace {

std::string level_name(int level) { return fmt::format("{:.4g}pct", 100.0 * kStrain[level]); }

std::vector<double> flatten(const std::vector<Vec3>& v) {
  std::vector<double> out;
  for (const Vec3& p : v) out.insert(out.end(), {p.x(), p.y(), p.z()});
  return out;
}

}  // namespace

std::string table(const Study& study, const StudyOptions& o) {
  std::ostringstream s;
  s << fmt::format(
      "Truth Cube: {}^3 hexahedra, plates {}, shape memory '{}' frame, reaction {}, volume "
      "constraint {}{}; FEM Neo-Hookean E = {:.4g} kPa, nu = {}\n",
      o.cells, o.sliding ? "sliding" : "holding without slip",
      o.frame == FrameMode::polar ? "polar" : "frame", o.reaction ? "on" : "off",
      o.volume_constraint ? "on" : "off",
      o.solver == StaticSolver::implicit ? ", implicit static solver" : "", o.young / 1e3,
      o.poisson);
  s << "strain  model  mean err  max err  eq.(1) mean  sum ratio  eq.(1) translated  "
       "paper Phymul  paper ANSYS  plate force\n";
  for (const LevelResult& r : study.results) {
    const Metrics& m = r.metrics;
    s << fmt::format(
        "{:5.2f}%  {:5}  {:5.2f} mm  {:5.2f} mm  {:9.1f} %  {:7.1f} %  {:15.1f} %  "
        "{:10.1f} %  {:9.1f} %  {:9.3f} N\n",
        100 * kStrain[r.level], r.model, m.mean_error_mm, m.max_error_mm, m.mean_relative_error_pct,
        m.sum_ratio_pct, m.mean_relative_error_pct_translated, kPaperPhymul[r.level],
        kPaperAnsys[r.level], r.plate_force);
  }
  return s.str();
}

std::string json(const Study& study, const StudyOptions& o) {
  std::string s = fmt::format(
      "{{\n  \"cells\": {},\n  \"plates\": \"{}\",\n  \"frame\": \"{}\",\n  \"reaction\": {},\n"
      "  \"volume_constraint\": {},\n  \"levels\": [\n",
      o.cells, o.sliding ? "sliding" : "no-slip", o.frame == FrameMode::polar ? "polar" : "frame",
      o.reaction, o.volume_constraint);
  for (size_t k = 0; k < study.results.size(); ++k) {
    const LevelResult& r = study.results[k];
    const Metrics& m = r.metrics;
    s += fmt::format(
        "    {{\"strain\": {}, \"model\": \"{}\", \"mean_error_mm\": {}, \"max_error_mm\": {}, "
        "\"mean_relative_error_pct\": {}, \"sum_ratio_pct\": {}, "
        "\"mean_relative_error_pct_translated\": {}, \"mean_error_mm_translated\": {}, "
        "\"paper_phymul_pct\": {}, \"paper_ansys_pct\": {}, \"iterations\": {}, "
        "\"seconds\": {}, \"plate_force_N\": {}}}{}\n",
        kStrain[r.level], r.model, m.mean_error_mm, m.max_error_mm, m.mean_relative_error_pct,
        m.sum_ratio_pct, m.mean_relative_error_pct_translated, m.mean_error_mm_translated,
        kPaperPhymul[r.level], kPaperAnsys[r.level], r.iterations, r.seconds, r.plate_force,
        k + 1 < study.results.size() ? "," : "");
  }
  return s + "  ]\n}\n";
}

void write_outputs(const Study& study, const std::vector<Bead>& beads, const StudyOptions& o,
                   const std::filesystem::path& dir) {
  std::filesystem::create_directories(dir);
  std::vector<Vec3> measured(beads.size()), rest(beads.size());
  for (const LevelResult& r : study.results) {
    const std::string stem = fmt::format("{}_{}", r.model, level_name(r.level));
    std::vector<Vec3> displacement(r.positions.size());
    for (size_t i = 0; i < r.positions.size(); ++i)
      displacement[i] = r.positions[i] - study.mesh.points[i];
    const auto u = flatten(displacement);
    const PointField mesh_fields[] = {{"displacement", 3, u}};
    write_vtu(dir / ("truthcube_" + stem + ".vtu"), r.positions, study.mesh.cells, mesh_fields, {});
    std::vector<Vec3> error(beads.size());
    for (size_t b = 0; b < beads.size(); ++b) {
      measured[b] = beads[b].compressed[r.level];
      error[b] = r.beads[b] - measured[b];
    }
    const auto m = flatten(measured), e = flatten(error);
    const PointField bead_fields[] = {{"measured", 3, m}, {"error", 3, e}};
    write_points_vtu(dir / ("beads_" + stem + ".vtu"), r.beads, bead_fields);
  }
  write_file_atomically(dir / "beads.csv", [&](std::ostream& out) {
    out << "model,strain,i,j,k,rest_x_m,rest_y_m,rest_z_m,measured_x_m,measured_y_m,"
           "measured_z_m,simulated_x_m,simulated_y_m,simulated_z_m\n";
    for (const LevelResult& r : study.results)
      for (size_t b = 0; b < beads.size(); ++b) {
        const Bead& d = beads[b];
        const Vec3& m = d.compressed[r.level];
        out << fmt::format("{},{},{},{},{},{},{},{},{},{},{},{},{},{}\n", r.model, kStrain[r.level],
                           d.index[0], d.index[1], d.index[2], d.rest.x(), d.rest.y(), d.rest.z(),
                           m.x(), m.y(), m.z(), r.beads[b].x(), r.beads[b].y(), r.beads[b].z());
      }
  });
  write_file_atomically(dir / "truthcube.json", [&](std::ostream& out) { out << json(study, o); });
}

}  // namespace phymul::truthcube
