// Box, ellipsoid and cylinder generators.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <functional>
#include <numbers>
#include <numeric>
#include <ostream>
#include <random>
#include <string>
#include <vector>

#include "mesh_test_util.hpp"
#include "phymul/mesh.hpp"

namespace phymul {
namespace {

using mesh_test::contains;
using mesh_test::total_measure;
using mesh_test::validation_error;

const Vec3 kCenter(0.1, -0.2, 0.3);

struct GeneratorCase {
  std::string name;
  std::function<Mesh()> make;
};

void PrintTo(const GeneratorCase& generator, std::ostream* out) { *out << generator.name; }

std::vector<GeneratorCase> generator_cases() {
  const Vec3 radii(0.03, 0.02, 0.01);
  return {
      {"box_hexa",
       [] {
         return make_box(Vec3(0.03, 0.02, 0.01), {6, 4, 3}, CellType::hexa, kCenter);
       }},
      {"box_tetra",
       [] {
         return make_box(Vec3(0.03, 0.02, 0.01), {6, 4, 3}, CellType::tetra, kCenter);
       }},
      {"ellipsoid_surface", [=] { return make_ellipsoid_surface(radii, 3, kCenter); }},
      {"ellipsoid_volume", [=] { return make_ellipsoid_volume(radii, 2, 3, kCenter); }},
      {"ellipsoid_volume_one_layer", [=] { return make_ellipsoid_volume(radii, 1, 1, kCenter); }},
      {"cylinder_surface", [] { return make_cylinder_surface(0.01, 0.04, 16, 5, kCenter); }},
      {"cylinder_volume", [] { return make_cylinder_volume(0.01, 0.04, 16, 5, 3, kCenter); }},
  };
}

double mean_edge_length(const Mesh& mesh) {
  const Adjacency adjacency = edge_neighbours(mesh);
  double sum = 0.0;
  for (int a = 0; a < adjacency.rows(); ++a) {
    for (int b : adjacency.row(a)) sum += (mesh.points[b] - mesh.points[a]).norm();
  }
  return sum / double(adjacency.indices.size());
}

// Moves every node by up to `fraction` of the mean edge length: quad faces stop being planar.
Mesh warped(Mesh mesh, double fraction) {
  std::mt19937 random(12345);
  std::uniform_real_distribution<double> unit(-1.0, 1.0);
  const double amplitude = fraction * mean_edge_length(mesh);
  for (Vec3& p : mesh.points) p += amplitude * Vec3(unit(random), unit(random), unit(random));
  return mesh;
}

// |a - b| <= tolerance * |b|, with the values in the failure message.
::testing::AssertionResult relative_near(double a, double b, double tolerance) {
  if (std::abs(a - b) <= tolerance * std::abs(b)) return ::testing::AssertionSuccess();
  return ::testing::AssertionFailure()
         << a << " vs " << b << ": relative difference " << std::abs(a - b) / std::abs(b);
}

class MeshEveryGenerator : public ::testing::TestWithParam<GeneratorCase> {};

TEST_P(MeshEveryGenerator, IsValidWithAClosedOutwardBoundary) {
  const Mesh mesh = GetParam().make();
  EXPECT_EQ(validation_error(mesh), "");
  const std::vector<Triangle> boundary = boundary_triangles(mesh);
  EXPECT_TRUE(is_closed(boundary));
  // Every generated shape is convex around its centre: each triangle faces away from it.
  for (const auto& [a, b, c] : boundary) {
    const Vec3& p = mesh.points[a];
    const Vec3 normal = (mesh.points[b] - p).cross(mesh.points[c] - p);
    ASSERT_GT(normal.dot((p + mesh.points[b] + mesh.points[c]) / 3.0 - kCenter), 0.0);
  }
  const double enclosed = enclosed_volume(mesh.points, boundary);
  EXPECT_GT(enclosed, 0.0);
  if (mesh.volumetric()) {
    EXPECT_TRUE(relative_near(total_measure(mesh), enclosed, 1e-12));
  }
}

// Non-planar quad faces: the cell volumes still add up to the enclosed volume because a
// shared quad is split identically from both of its cells and on the boundary.
TEST_P(MeshEveryGenerator, WarpedCopyKeepsCellAndEnclosedVolumesEqual) {
  const Mesh mesh = warped(GetParam().make(), 0.02);
  EXPECT_EQ(validation_error(mesh), "");
  const std::vector<Triangle> boundary = boundary_triangles(mesh);
  EXPECT_TRUE(is_closed(boundary));
  if (mesh.volumetric()) {
    EXPECT_TRUE(relative_near(total_measure(mesh), enclosed_volume(mesh.points, boundary), 1e-12));
  }
}

TEST_P(MeshEveryGenerator, LumpedMeasureSumsToTheTotal) {
  const Mesh mesh = GetParam().make();
  const std::vector<double> lumped = lumped_measure(mesh);
  ASSERT_EQ(lumped.size(), mesh.points.size());
  EXPECT_TRUE(relative_near(std::accumulate(lumped.begin(), lumped.end(), 0.0), total_measure(mesh),
                            1e-12));
  EXPECT_GT(*std::min_element(lumped.begin(), lumped.end()), 0.0);  // no orphan nodes
}

TEST_P(MeshEveryGenerator, NodeSetsAreSortedUniqueAndInRange) {
  const Mesh mesh = GetParam().make();
  ASSERT_FALSE(mesh.node_sets.empty());
  for (const auto& [name, nodes] : mesh.node_sets) {
    ASSERT_FALSE(nodes.empty()) << name;
    EXPECT_TRUE(std::adjacent_find(nodes.begin(), nodes.end(), std::greater_equal<>()) ==
                nodes.end())
        << name << " is not sorted and unique";
    EXPECT_GE(nodes.front(), 0) << name;
    EXPECT_LT(nodes.back(), int(mesh.points.size())) << name;
  }
}

INSTANTIATE_TEST_SUITE_P(All, MeshEveryGenerator, ::testing::ValuesIn(generator_cases()),
                         [](const auto& info) { return info.param.name; });

TEST(MeshMakeBox, HexaVolumesSumToTheBoxVolume) {
  const Mesh mesh = make_box(Vec3(0.3, 0.2, 0.1), {3, 4, 5}, CellType::hexa, kCenter);
  ASSERT_EQ(mesh.points.size(), 4u * 5u * 6u);
  ASSERT_EQ(mesh.cells.size(), 60u);
  for (const Cell& cell : mesh.cells) {
    EXPECT_TRUE(relative_near(cell_measure(mesh.points, cell), 0.006 / 60.0, 1e-12));
  }
  EXPECT_TRUE(relative_near(total_measure(mesh), 0.006, 1e-12));
  Vec3 low = mesh.points[0], high = mesh.points[0];
  for (const Vec3& p : mesh.points) {
    low = low.cwiseMin(p);
    high = high.cwiseMax(p);
  }
  EXPECT_LT((low - (kCenter - Vec3(0.15, 0.1, 0.05))).norm(), 1e-15);
  EXPECT_LT((high - (kCenter + Vec3(0.15, 0.1, 0.05))).norm(), 1e-15);
}

TEST(MeshMakeBox, TetraSplitIsConformingAndSumsToTheBoxVolume) {
  const Mesh mesh = make_box(Vec3(0.3, 0.2, 0.1), {3, 4, 5}, CellType::tetra, kCenter);
  ASSERT_EQ(mesh.cells.size(), 6u * 60u);
  for (const Cell& cell : mesh.cells) {
    ASSERT_EQ(cell.type, CellType::tetra);
    EXPECT_TRUE(relative_near(cell_measure(mesh.points, cell), 0.006 / 360.0, 1e-12));
  }
  EXPECT_TRUE(relative_near(total_measure(mesh), 0.006, 1e-12));
  // Conforming: only the outer faces are left, two triangles per boundary grid square.
  const std::vector<Triangle> boundary = boundary_triangles(mesh);
  EXPECT_EQ(boundary.size(), 2u * 2u * (3u * 4u + 4u * 5u + 3u * 5u));
  EXPECT_TRUE(is_closed(boundary));
}

TEST(MeshMakeBox, NodeSetsLieOnTheirFaces) {
  const Vec3 size(0.3, 0.2, 0.1);
  for (CellType type : {CellType::hexa, CellType::tetra}) {
    const Mesh mesh = make_box(size, {3, 3, 3}, type, kCenter);
    const std::vector<std::pair<std::string, std::pair<int, double>>> faces{
        {"left", {0, -1.0}}, {"right", {0, 1.0}},   {"front", {1, -1.0}},
        {"back", {1, 1.0}},  {"bottom", {2, -1.0}}, {"top", {2, 1.0}}};
    for (const auto& [name, face] : faces) {
      const auto& [axis, side] = face;
      ASSERT_TRUE(mesh.node_sets.count(name)) << name;
      const std::vector<int>& nodes = mesh.node_sets.at(name);
      EXPECT_EQ(nodes.size(), 16u) << name;  // (n + 1)^2
      for (int node : nodes) {
        EXPECT_NEAR(mesh.points[node][axis], kCenter[axis] + side * 0.5 * size[axis], 1e-15);
      }
    }
  }
  const Mesh uneven = make_box(size, {2, 3, 4}, CellType::hexa);
  EXPECT_EQ(uneven.node_sets.at("left").size(), 4u * 5u);
  EXPECT_EQ(uneven.node_sets.at("front").size(), 3u * 5u);
  EXPECT_EQ(uneven.node_sets.at("top").size(), 3u * 4u);
}

TEST(MeshMakeEllipsoid, SurfaceIsASubdividedIcosahedronOnTheEllipsoid) {
  const Vec3 radii(0.03, 0.02, 0.01);
  for (int s = 0; s <= 4; ++s) {
    const Mesh mesh = make_ellipsoid_surface(radii, s, kCenter);
    const std::size_t faces = 20u << (2 * s);
    EXPECT_EQ(mesh.cells.size(), faces);
    EXPECT_EQ(mesh.points.size(), faces / 2 + 2);
    for (const Vec3& p : mesh.points) {
      EXPECT_NEAR((p - kCenter).cwiseQuotient(radii).squaredNorm(), 1.0, 1e-13);
    }
    const int top = mesh.node_sets.at("top").at(0), bottom = mesh.node_sets.at("bottom").at(0);
    EXPECT_NEAR(mesh.points[top].z(), kCenter.z() + radii.z(), 1e-15);
    EXPECT_NEAR(mesh.points[bottom].z(), kCenter.z() - radii.z(), 1e-15);
    for (std::size_t i = 0; i < mesh.points.size(); ++i) {
      if (int(i) != top) {
        EXPECT_LT(mesh.points[i].z(), mesh.points[top].z());
      }
      if (int(i) != bottom) {
        EXPECT_GT(mesh.points[i].z(), mesh.points[bottom].z());
      }
    }
  }
}

// The inscribed polyhedron's volume error shrinks about 4 times per subdivision.
TEST(MeshMakeEllipsoid, VolumeApproachesTheAnalyticVolume) {
  const Vec3 radii(0.03, 0.02, 0.01);
  const double exact = 4.0 / 3.0 * std::numbers::pi * radii.prod();
  double previous_error = 1.0;
  for (int s = 0; s <= 7; ++s) {
    const Mesh surface = make_ellipsoid_surface(radii, s);
    const double volume = enclosed_volume(surface.points, boundary_triangles(surface));
    const double error = (exact - volume) / exact;
    std::printf("ellipsoid subdivisions %d: relative volume deficit %.3e\n", s, error);
    EXPECT_GT(error, 0.0);  // inscribed
    if (s >= 2) {
      EXPECT_LT(error, previous_error / 3.7);
    }
    previous_error = error;
  }
  EXPECT_LT(previous_error, 4e-5);  // measured 3.38e-5 at subdivisions 7
}

TEST(MeshMakeEllipsoid, VolumeMeshBoundaryIsTheSurfaceMesh) {
  const Vec3 radii(0.03, 0.02, 0.01);
  const Mesh surface = make_ellipsoid_surface(radii, 2, kCenter);
  const Mesh volume = make_ellipsoid_volume(radii, 2, 4, kCenter);
  const std::size_t per_shell = surface.points.size();
  EXPECT_EQ(volume.points.size(), 1u + 4u * per_shell);
  EXPECT_EQ(volume.cells.size(), 4u * surface.cells.size());  // 1 tetra + 3 wedges per triangle
  const std::vector<int>& outer = volume.node_sets.at("surface");
  ASSERT_EQ(outer.size(), per_shell);
  std::vector<Triangle> expected;
  for (const Cell& cell : surface.cells) {
    expected.push_back(
        {cell.nodes[0] + outer[0], cell.nodes[1] + outer[0], cell.nodes[2] + outer[0]});
  }
  std::vector<Triangle> boundary = boundary_triangles(volume);
  std::sort(expected.begin(), expected.end());
  std::sort(boundary.begin(), boundary.end());
  EXPECT_EQ(boundary, expected);
  for (std::size_t v = 0; v < per_shell; ++v) {
    EXPECT_LT((volume.points[outer[v]] - surface.points[v]).norm(), 1e-16);
  }
  EXPECT_EQ(volume.points[volume.node_sets.at("top")[0]],
            surface.points[surface.node_sets.at("top")[0]]);
  EXPECT_TRUE(relative_near(total_measure(volume),
                            enclosed_volume(surface.points, boundary_triangles(surface)), 1e-12));
}

TEST(MeshMakeEllipsoid, OneTetraPerTriangleAndAWedgePerTriangleAndLayer) {
  const Mesh one = make_ellipsoid_volume(Vec3::Ones(), 1, 1);
  EXPECT_EQ(one.cells.size(), 80u);
  EXPECT_TRUE(std::all_of(one.cells.begin(), one.cells.end(),
                          [](const Cell& c) { return c.type == CellType::tetra; }));
  const Mesh three = make_ellipsoid_volume(Vec3::Ones(), 1, 3);
  EXPECT_EQ(std::count_if(three.cells.begin(), three.cells.end(),
                          [](const Cell& c) { return c.type == CellType::wedge; }),
            160);
}

double prism_volume(double radius, double length, int around) {
  return 0.5 * around * radius * radius * std::sin(2.0 * std::numbers::pi / around) * length;
}

TEST(MeshMakeCylinder, SurfaceEnclosesTheInscribedPrism) {
  const double radius = 0.01, length = 0.04;
  const Mesh mesh = make_cylinder_surface(radius, length, 16, 5, kCenter);
  EXPECT_EQ(mesh.points.size(), 16u * 6u + 2u);
  EXPECT_EQ(mesh.cells.size(), 2u * 16u * 5u + 2u * 16u);
  EXPECT_TRUE(relative_near(enclosed_volume(mesh.points, boundary_triangles(mesh)),
                            prism_volume(radius, length, 16), 1e-12));
  EXPECT_EQ(mesh.node_sets.at("side").size(), 16u * 6u);
  for (int node : mesh.node_sets.at("side")) {
    EXPECT_NEAR((mesh.points[node] - kCenter).head<2>().norm(), radius, 1e-15);
  }
  for (const char* cap : {"top", "bottom"}) {
    const double z = kCenter.z() + (cap == std::string("top") ? 0.5 : -0.5) * length;
    EXPECT_EQ(mesh.node_sets.at(cap).size(), 17u) << cap;
    for (int node : mesh.node_sets.at(cap)) EXPECT_NEAR(mesh.points[node].z(), z, 1e-15) << cap;
  }
}

TEST(MeshMakeCylinder, VolumeMeshFillsTheInscribedPrism) {
  const double radius = 0.01, length = 0.04;
  const Mesh mesh = make_cylinder_volume(radius, length, 16, 5, 3, kCenter);
  EXPECT_TRUE(relative_near(total_measure(mesh), prism_volume(radius, length, 16), 1e-12));
  EXPECT_EQ(mesh.node_sets.at("side").size(), 16u * 6u);
  for (int node : mesh.node_sets.at("side")) {
    EXPECT_NEAR((mesh.points[node] - kCenter).head<2>().norm(), radius, 1e-15);
  }
  const std::size_t disk = mesh.points.size() / 6;
  EXPECT_EQ(mesh.node_sets.at("top").size(), disk);
  for (int node : mesh.node_sets.at("top")) {
    EXPECT_NEAR(mesh.points[node].z(), kCenter.z() + 0.5 * length, 1e-15);
  }
  for (int node : mesh.node_sets.at("bottom")) {
    EXPECT_NEAR(mesh.points[node].z(), kCenter.z() - 0.5 * length, 1e-15);
  }
}

// Smallest angle (degrees) of the wedges' triangles: the disk stays well shaped.
double smallest_disk_angle(const Mesh& mesh) {
  double smallest = 180.0;
  for (const Cell& cell : mesh.cells) {
    for (int k = 0; k < 3; ++k) {
      const Vec3& p = mesh.points[cell.nodes[k]];
      const Vec3 u = mesh.points[cell.nodes[(k + 1) % 3]] - p;
      const Vec3 v = mesh.points[cell.nodes[(k + 2) % 3]] - p;
      smallest = std::min(smallest,
                          std::acos(u.normalized().dot(v.normalized())) * 180.0 / std::numbers::pi);
    }
  }
  return smallest;
}

TEST(MeshMakeCylinder, VolumeMeshIsValidAndWellShapedForManyParameters) {
  double worst_angle = 180.0;
  for (int around = 3; around <= 72; ++around) {
    for (int rings = 1; rings <= 10; ++rings) {
      const Mesh mesh = make_cylinder_volume(0.01, 0.02, around, 2, rings);
      ASSERT_EQ(validation_error(mesh), "") << around << " around, " << rings << " rings";
      ASSERT_TRUE(relative_near(total_measure(mesh), prism_volume(0.01, 0.02, around), 1e-12));
      ASSERT_TRUE(is_closed(boundary_triangles(mesh)));
      // The rim has `around` nodes whatever the number of rings.
      ASSERT_EQ(mesh.node_sets.at("side").size(), 3u * around);
      if (around >= 4 * rings && around <= 8 * rings) {  // rim spacing close to ring spacing
        worst_angle = std::min(worst_angle, smallest_disk_angle(mesh));
      }
    }
  }
  std::printf("smallest disk triangle angle (4 rings <= around <= 8 rings): %.1f deg\n",
              worst_angle);
  EXPECT_GT(worst_angle, 30.0);
}

std::string argument_error(const std::function<void()>& make) {
  try {
    make();
  } catch (const std::invalid_argument& e) {
    return e.what();
  }
  return "";
}

TEST(MeshGenerators, RejectBadArgumentsNamingThem) {
  const Vec3 one = Vec3::Ones();
  EXPECT_EQ(argument_error([&] {
              make_box(one, {2, 2, 0}, CellType::hexa);
            }),
            "make_box: cells[2] must be >= 1 (got 0)");
  EXPECT_EQ(argument_error([&] {
              make_box(Vec3(1, -2, 1), {2, 2, 2}, CellType::hexa);
            }),
            "make_box: size[1] must be a finite length > 0 m (got -2)");
  EXPECT_EQ(argument_error([&] {
              make_box(one, {2, 2, 2}, CellType::wedge);
            }),
            "make_box: type must be hexa or tetra (got wedge)");
  EXPECT_TRUE(contains(argument_error([&] {
                         make_box(one, {1000, 1000, 1000}, CellType::hexa);
                       }),
                       "make_box: cells (1000, 1000, 1000) would give 1e+09 nodes"));
  EXPECT_EQ(argument_error([&] { make_ellipsoid_surface(one, 8); }),
            "make_ellipsoid_surface: subdivisions must be in 0..7 (got 8)");
  EXPECT_EQ(argument_error([&] { make_ellipsoid_surface(Vec3(1, 1, 0), 2); }),
            "make_ellipsoid_surface: radii[2] must be a finite length > 0 m (got 0)");
  EXPECT_EQ(argument_error([&] { make_ellipsoid_volume(one, 2, 0); }),
            "make_ellipsoid_volume: layers must be >= 1 (got 0)");
  EXPECT_EQ(argument_error([&] { make_cylinder_surface(0.01, 0.02, 2, 1); }),
            "make_cylinder_surface: around must be >= 3 (got 2)");
  EXPECT_EQ(argument_error([&] { make_cylinder_surface(0.01, 0.0, 8, 1); }),
            "make_cylinder_surface: length must be a finite length > 0 m (got 0)");
  EXPECT_EQ(argument_error([&] { make_cylinder_volume(-0.01, 0.02, 8, 1, 1); }),
            "make_cylinder_volume: radius must be a finite length > 0 m (got -0.01)");
  EXPECT_EQ(argument_error([&] { make_cylinder_volume(0.01, 0.02, 8, 0, 1); }),
            "make_cylinder_volume: along must be >= 1 (got 0)");
  EXPECT_EQ(argument_error([&] { make_cylinder_volume(0.01, 0.02, 8, 1, 0); }),
            "make_cylinder_volume: rings must be >= 1 (got 0)");
  EXPECT_TRUE(
      contains(argument_error([&] { make_ellipsoid_surface(one, 1, Vec3(0, std::nan(""), 0)); }),
               "make_ellipsoid_surface: center must be finite"));
}

}  // namespace
}  // namespace phymul
