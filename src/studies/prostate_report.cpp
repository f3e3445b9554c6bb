// The prostate study's table, JSON and result files.
#include <fmt/format.h>

#include <filesystem>
#include <fstream>

#include "phymul/studies/prostate.hpp"
#include "phymul/vtk.hpp"

namespace phymul::prostate {

std::string table(const Study& study) {
  std::string t =
      fmt::format("{:>9} {:>9} {:>12} {:>11} {:>12} {:>10} {:>12} {:>9}\n", "bladder", "probe",
                  "deformation", "centre", "centre lift", "probe", "volume err", "stitched");
  t += fmt::format("{:>9} {:>9} {:>12} {:>11} {:>12} {:>10} {:>12} {:>9}\n", "mL", "", "% height",
                   "mm", "mm", "N", "relative", "nodes");
  for (const FillingResult& r : study.results)
    t += fmt::format("{:>9.0f} {:>9} {:>12.2f} {:>11.3f} {:>12.3f} {:>10.3f} {:>12.1e} {:>9}\n",
                     r.filling * 1e6, probe_name(r.probe), r.prostate_deformation_pct,
                     r.centre_displacement * 1e3, r.centre_lift * 1e3, r.probe_force,
                     (r.bladder_volume - r.filling) / r.filling, r.stitched.size());
  return t;
}

std::string json(const Study& study) {
  std::string j = "{\n  \"fillings\": [";
  for (size_t k = 0; k < study.results.size(); ++k) {
    const FillingResult& r = study.results[k];
    j += fmt::format(
        "{}\n    {{\"bladder_volume_ml\": {:.17g}, \"target_volume_ml\": {:.17g}, "
        "\"probe\": \"{}\", \"prostate_deformation_pct\": {:.17g}, "
        "\"prostate_height_mm\": {:.17g}, \"centre_displacement_mm\": {:.17g}, "
        "\"centre_lift_mm\": {:.17g}, \"probe_force_n\": {:.17g}, "
        "\"pressure_resultant_n\": {:.17g}, \"stitched_nodes\": {}, "
        "\"iterations\": {}}}",
        k ? "," : "", r.bladder_volume * 1e6, r.filling * 1e6, probe_name(r.probe),
        r.prostate_deformation_pct, r.prostate_height * 1e3, r.centre_displacement * 1e3,
        r.centre_lift * 1e3, r.probe_force, r.pressure_resultant, r.stitched.size(), r.iterations);
  }
  j += fmt::format("\n  ],\n  \"prostate_stiffness_n_per_m\": {:.17g},\n  \"wall_time_s\": {:.6g}",
                   study.options.prostate_stiffness, study.wall_time);
  if (!study.real_time.empty()) {
    j += ",\n  \"real_time\": [";
    for (size_t k = 0; k < study.real_time.size(); ++k) {
      const RealTimeRun& r = study.real_time[k];
      j += fmt::format(
          "{}\n    {{\"bladder_volume_ml\": {:.6g}, \"probe\": \"{}\", \"steps\": {}, "
          "\"dt_s\": {:.6g}, \"wall_time_s\": {:.6g}, \"real_time_factor\": {:.6g}, "
          "\"cpu_real_time_factor\": {:.6g}, \"stepping_real_time_factor\": {:.6g}, "
          "\"added_mass_pct\": {:.6g}}}",
          k ? "," : "", r.filling * 1e6, probe_name(r.probe), r.steps, r.dt, r.wall_time,
          r.real_time_factor, r.cpu_real_time_factor, r.stepping_real_time_factor,
          r.added_mass_pct);
    }
    j += fmt::format("\n  ],\n  \"real_time_factor\": {:.6g}", study.real_time_factor);
  }
  return j + "\n}\n";
}

}  // namespace phymul::prostate
