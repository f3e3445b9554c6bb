// `phymul mesh --remesh`: a jittered, unevenly refined sphere written as STL by meshio,
// remeshed, and read back by meshio.
#include <fmt/format.h>
#include <gtest/gtest.h>

#include <cstdio>
#include <fstream>

#include "support/process.hpp"

namespace phymul {
namespace {

using testing::cli;
using testing::read_text;
using testing::run_command;
using testing::TempDir;

// A sphere of radius 40 (mm): a UV sphere crowded at the poles (a segmentation's triangles
// of every size), jittered along the sphere, written by meshio as binary STL. Then, given the
// remeshed .vtu, prints its point count, mean edge and largest |r - 40|.
constexpr const char* kScript = R"(import sys, numpy as np
try:
    import meshio
except ImportError:
    print('NO MESHIO'); sys.exit(0)
if sys.argv[1] == 'write':
    rng = np.random.default_rng(3)
    rings, around, r = 60, 80, 40.0
    th = np.linspace(0, np.pi, rings + 1)[1:-1]
    ph = np.linspace(0, 2 * np.pi, around, endpoint=False)
    T, P = np.meshgrid(th, ph, indexing='ij')
    T = T + rng.normal(0, 0.1 * np.pi / rings, T.shape)
    P = P + rng.normal(0, 0.1 * 2 * np.pi / around, P.shape)
    pts = np.c_[np.sin(T).ravel() * np.cos(P).ravel(), np.sin(T).ravel() * np.sin(P).ravel(),
                np.cos(T).ravel()] * r
    pts = np.vstack([[0, 0, r], pts, [0, 0, -r]])
    idx = lambda i, j: 1 + i * around + j % around
    tri = [[0, idx(0, j), idx(0, j + 1)] for j in range(around)]
    for i in range(rings - 2):
        for j in range(around):
            tri += [[idx(i, j), idx(i + 1, j), idx(i + 1, j + 1)],
                    [idx(i, j), idx(i + 1, j + 1), idx(i, j + 1)]]
    s = len(pts) - 1
    tri += [[s, idx(rings - 2, j + 1), idx(rings - 2, j)] for j in range(around)]
    meshio.Mesh(pts, [('triangle', np.array(tri))]).write(sys.argv[2], binary=True)
    print('OK')
else:
    m = meshio.read(sys.argv[2])
    t = m.cells_dict['triangle']
    e = np.unique(np.sort(np.r_[t[:, [0, 1]], t[:, [1, 2]], t[:, [2, 0]]], axis=1), axis=0)
    length = np.linalg.norm(m.points[e[:, 0]] - m.points[e[:, 1]], axis=1)
    print(f'OK {len(m.points)} {length.mean():.6f} {np.abs(np.linalg.norm(m.points, axis=1) - 40).max():.6f}')
)";

TEST(MeshCli, RemeshWritesTheSurfaceAtTheEdgeWithItsQuality) {
  TempDir dir;
  const auto script = dir.path() / "sphere.py", stl = dir.path() / "bladder.stl",
             out = dir.path() / "bladder_8mm.vtu";
  std::ofstream(script) << kScript;
  const auto made =
      run_command(fmt::format("/usr/bin/python3 {} write {}", script.string(), stl.string()));
  if (made.output.find("NO MESHIO") != std::string::npos) GTEST_SKIP() << "no meshio";
  ASSERT_NE(made.output.find("OK"), std::string::npos) << made.output;
  const auto r = run_command(fmt::format("{} mesh {} --units mm --remesh '8 mm' -o {}", cli(),
                                         stl.string(), out.string()));
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("smallest angle"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("coordinates in mm"), std::string::npos) << r.output;
  const auto back =
      run_command(fmt::format("/usr/bin/python3 {} read {}", script.string(), out.string()));
  int points = 0;
  double mean = 0.0, off = 0.0;
  ASSERT_EQ(std::sscanf(back.output.c_str(), "OK %d %lf %lf", &points, &mean, &off), 3)
      << back.output;
  EXPECT_NEAR(mean, 8.0, 0.2 * 8.0);
  // On the input's triangles, inside the sphere by at most their chord depth: edges of at
  // most 2 pi 40 / 80 = 3.1 mm give 3.1^2 / (8 * 40) = 0.03 mm; 0.1 with the jitter.
  EXPECT_LT(off, 0.1);
  // 4 pi 40^2 / (sqrt(3)/4 8^2) = 725 triangles, ~365 points.
  EXPECT_GT(points, 250);
  EXPECT_LT(points, 500);
}

TEST(MeshCli, AnEdgeLongerThanTheSurfaceIsAnErrorWithTheRange) {
  const auto r = run_command(
      fmt::format("{} mesh {} --remesh '5 m' -o /tmp/never.vtu", cli(),
                  (testing::source_dir() / "tests/data/surfaces/octahedron.stl").string()));
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_NE(r.output.find("the edge must be in ["), std::string::npos) << r.output;
  const auto none = run_command(
      fmt::format("{} mesh {} -o /tmp/never.vtu", cli(),
                  (testing::source_dir() / "tests/data/surfaces/octahedron.stl").string()));
  EXPECT_EQ(none.exit_code, 1);
  EXPECT_NE(none.output.find("--remesh"), std::string::npos) << none.output;
}

}  // namespace
}  // namespace phymul
