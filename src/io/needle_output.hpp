// What the result files say of needles (docs/needles.md): their frames (shaft polyline, track
// points, target), their monitors.csv columns, their punctures for report.json.
#pragma once

#include <filesystem>
#include <string>
#include <vector>

#include "phymul/data.hpp"
#include "phymul/run.hpp"

namespace phymul {

// One .vtu (ASCII): per needle a line from its base to its tip (cell `kind` 0), a vertex per
// track point (1) and at its target (2); cell `needle` is the needle's index.
void write_needle_frame(const std::filesystem::path& path, const Model& model, const Data& data);

// The monitors.csv header's needle columns (each with its leading comma), and a row's.
std::string needle_monitor_header(const Model& model);
std::string needle_monitor_row(const Model& model, const Data& data);

// Every puncture so far, in order per needle.
std::vector<NeedlePuncture> needle_punctures(const Model& model, const Data& data);

}  // namespace phymul
