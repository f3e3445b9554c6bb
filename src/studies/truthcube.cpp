#include "phymul/studies/truthcube.hpp"

#include <fmt/format.h>

#include <charconv>
#include <cmath>
#include <fstream>
#include <stdexcept>

namespace phymul::truthcube {
namespace {

constexpr int kHeaderLines = 7;
constexpr int kColumns = 15;  // i, j, k, then x y z at rest and at each level

std::vector<std::string> split(const std::string& line) {
  std::vector<std::string> fields;
  size_t start = 0;
  for (;;) {
    const size_t comma = line.find(',', start);
    fields.push_back(line.substr(start, comma - start));
    if (comma == std::string::npos) break;
    start = comma + 1;
  }
  if (!fields.empty() && !fields.back().empty() && fields.back().back() == '\r')
    fields.back().pop_back();
  return fields;
}

double number(const std::string& field, const std::string& where, const char* column) {
  double value = 0.0;
  const auto [end, ec] = std::from_chars(field.data(), field.data() + field.size(), value);
  if (ec != std::errc{} || end != field.data() + field.size() || !std::isfinite(value))
    throw std::runtime_error(
        fmt::format("{}: column '{}' must be a finite number (got '{}')", where, column, field));
  return value;
}

}  // namespace

std::vector<Bead> load_beads(const std::filesystem::path& csv) {
  static const char* kNames[kColumns] = {"i",  "j",  "k",  "x0", "y0", "z0", "x1", "y1",
                                         "z1", "x2", "y2", "z2", "x3", "y3", "z3"};
  std::ifstream in(csv);
  if (!in) throw std::runtime_error(fmt::format("cannot read Truth Cube data '{}'", csv.string()));
  std::vector<Bead> beads;
  std::string line;
  for (int number_of_line = 1; std::getline(in, line); ++number_of_line) {
    if (number_of_line <= kHeaderLines) continue;
    if (line.empty() || line == "\r") continue;
    const std::string where = fmt::format("{}:{}", csv.string(), number_of_line);
    const auto fields = split(line);
    if (fields.size() != kColumns)
      throw std::runtime_error(fmt::format("{}: expected {} comma-separated fields, got {}", where,
                                           kColumns, fields.size()));
    double v[kColumns];
    for (int c = 0; c < kColumns; ++c) v[c] = number(fields[c], where, kNames[c]);
    Bead b;
    for (int a = 0; a < 3; ++a) {
      if (v[a] != std::floor(v[a]) || v[a] < 1 || v[a] > 7)
        throw std::runtime_error(fmt::format(
            "{}: column '{}' must be an integer in [1, 7] (got {})", where, kNames[a], v[a]));
      b.index[a] = int(v[a]);
    }
    constexpr double mm = 1e-3;
    b.rest = Vec3(v[3], v[4], v[5]) * mm;
    for (int l = 0; l < kLevels; ++l)
      b.compressed[l] = Vec3(v[6 + 3 * l], v[7 + 3 * l], v[8 + 3 * l]) * mm;
    beads.push_back(b);
  }
  if (beads.size() != 343)
    throw std::runtime_error(
        fmt::format("{}: expected 343 beads (7 x 7 x 7), found {}", csv.string(), beads.size()));
  return beads;
}

CubeFrame locate_cube(const std::vector<Bead>& beads) {
  // Beads are 1 cm apart with a 1 cm margin: the base face lies 1 cm beyond layer k = 1.
  Vec3 mean = Vec3::Zero();
  double base_layer_z = 0.0;
  int base_layer = 0;
  for (const Bead& b : beads) {
    mean += b.rest;
    if (b.index[2] == 1) base_layer_z += b.rest.z(), ++base_layer;
  }
  mean /= double(beads.size());
  CubeFrame f;
  f.base_z = base_layer_z / base_layer + 0.010;
  f.plate_z = f.base_z - kEdge;
  f.center = Vec3(mean.x(), mean.y(), 0.5 * (f.base_z + f.plate_z));
  return f;
}

Embedding embed(const Mesh& box, const std::vector<Vec3>& points) {
  Embedding e;
  for (const Vec3& p : points) {
    bool found = false;
    for (const Cell& cell : box.cells) {
      Vec3 lo = box.points[cell.nodes[0]], hi = lo;
      for (int n : cell.node_span())
        lo = lo.cwiseMin(box.points[n]), hi = hi.cwiseMax(box.points[n]);
      const double slack = 1e-12;
      if ((p.array() < lo.array() - slack).any() || (p.array() > hi.array() + slack).any())
        continue;
      const Vec3 s = (p - lo).cwiseQuotient(hi - lo);  // local coordinates in [0, 1]^3
      std::array<int, 8> nodes{};
      std::array<double, 8> weights{};
      for (int k = 0; k < 8; ++k) {
        const int n = cell.nodes[k];
        const Vec3 corner = (box.points[n] - lo).cwiseQuotient(hi - lo);  // 0 or 1 per axis
        double w = 1.0;
        for (int a = 0; a < 3; ++a) w *= corner[a] > 0.5 ? s[a] : 1.0 - s[a];
        nodes[k] = n;
        weights[k] = w;
      }
      e.nodes.push_back(nodes);
      e.weights.push_back(weights);
      found = true;
      break;
    }
    if (!found)
      throw std::runtime_error(fmt::format("point ({:.4g}, {:.4g}, {:.4g}) m lies outside the mesh",
                                           p.x(), p.y(), p.z()));
  }
  return e;
}

std::vector<Vec3> Embedding::apply(const std::vector<Vec3>& positions) const {
  std::vector<Vec3> out(nodes.size(), Vec3::Zero());
  for (size_t b = 0; b < nodes.size(); ++b)
    for (int k = 0; k < 8; ++k) out[b] += weights[b][k] * positions[nodes[b][k]];
  return out;
}

Metrics compare(const std::vector<Bead>& beads, int level, const std::vector<Vec3>& simulated) {
  Metrics m;
  const double n = double(beads.size());
  Vec3 shift = Vec3::Zero();  // the translation that best aligns simulated with measured
  for (size_t b = 0; b < beads.size(); ++b) shift += beads[b].compressed[level] - simulated[b];
  shift /= n;
  double sum_error = 0.0, sum_displacement = 0.0;
  for (size_t b = 0; b < beads.size(); ++b) {
    const Vec3& measured = beads[b].compressed[level];
    const double error = (simulated[b] - measured).norm();
    const double error_translated = (simulated[b] + shift - measured).norm();
    const double displacement = (measured - beads[b].rest).norm();
    m.mean_error_mm += 1e3 * error / n;
    m.max_error_mm = std::max(m.max_error_mm, 1e3 * error);
    m.mean_relative_error_pct += 100.0 * error / displacement / n;
    m.mean_relative_error_pct_translated += 100.0 * error_translated / displacement / n;
    m.mean_error_mm_translated += 1e3 * error_translated / n;
    sum_error += error;
    sum_displacement += displacement;
  }
  m.sum_ratio_pct = 100.0 * sum_error / sum_displacement;
  return m;
}

}  // namespace phymul::truthcube
