// The prostate study's table, JSON and result files.
#include <fmt/format.h>

#include <filesystem>
#include <fstream>

#include "phymul/scene_words.hpp"
#include "phymul/studies/prostate.hpp"
#include "phymul/vtk.hpp"

namespace phymul::prostate {

std::string table(const Study& study) {
  // The last four columns: where the probe's force goes (N, upward on the prostate taken by
  // each path, FillingResult): the neck, the contact beyond it, the lateral holds, and what
  // the bladder's top node holds up.
  std::string t = fmt::format("support: {}\n", support_name(study.options.support));
  const auto row = [](auto... cells) {
    return fmt::format(
        "{:>9} {:>9} {:>12} {:>11} {:>12} {:>10} {:>12} {:>9} {:>7} {:>8} {:>7} "
        "{:>9}\n",
        cells...);
  };
  t += row("bladder", "probe", "deformation", "centre", "centre lift", "probe", "volume err",
           "stitched", "neck", "contact", "holds", "top node");
  t += row("mL", "", "% height", "mm", "mm", "N", "relative", "nodes", "N", "N", "N", "N");
  for (const FillingResult& r : study.results)
    t +=
        row(fmt::format("{:.0f}", r.filling * 1e6), probe_name(r.probe),
            fmt::format("{:.2f}", r.prostate_deformation_pct),
            fmt::format("{:.3f}", r.centre_displacement * 1e3),
            fmt::format("{:.3f}", r.centre_lift * 1e3), fmt::format("{:.3f}", r.probe_force),
            fmt::format("{:.1e}", (r.bladder_volume - r.filling) / r.filling), r.stitched.size(),
            fmt::format("{:.3f}", 0.0 - r.neck_force), fmt::format("{:.3f}", 0.0 - r.contact_force),
            fmt::format("{:.3f}", 0.0 - r.hold_force), fmt::format("{:.3f}", r.top_node_force));
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
        "\"pressure_resultant_n\": {:.17g}, \"neck_force_n\": {:.17g}, "
        "\"contact_force_n\": {:.17g}, \"hold_force_n\": {:.17g}, "
        "\"top_node_force_n\": {:.17g}, \"stitched_nodes\": {}, \"iterations\": {}}}",
        k ? "," : "", r.bladder_volume * 1e6, r.filling * 1e6, probe_name(r.probe),
        r.prostate_deformation_pct, r.prostate_height * 1e3, r.centre_displacement * 1e3,
        r.centre_lift * 1e3, r.probe_force, r.pressure_resultant, r.neck_force, r.contact_force,
        r.hold_force, r.top_node_force, r.stitched.size(), r.iterations);
  }
  j += fmt::format(
      "\n  ],\n  \"support\": \"{}\",\n  \"static_solver\": \"{}\",\n"
      "  \"relaxation\": \"{}\",\n  \"prostate_stiffness_n_per_m\": {:.17g},\n"
      "  \"bladder_stiffness_n_per_m\": {:.17g},\n  \"wall_time_s\": {:.6g}",
      support_name(study.options.support), scene_word(study.options.static_solver),
      scene_word(study.options.relaxation), study.options.prostate_stiffness,
      study.options.bladder_stiffness, study.wall_time);
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
