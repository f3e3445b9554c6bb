// CalculiX (ccx) cross-check of the reference FEM. The deck writer and the .dat reader are
// tested on their own; with ccx installed, small problems with exact answers prove the node
// orders and the material mapping, then the bonded 80 mm cube is solved by ccx and by
// phymul::fem::solve_static and the two must agree. Without ccx those tests are skipped
// loudly: the cross-check did not run.
#include "support/calculix.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cctype>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <random>
#include <sstream>
#include <string>
#include <vector>

#include "phymul/fem.hpp"
#include "phymul/mesh.hpp"

namespace phymul::fem {
namespace {

namespace fs = std::filesystem;

constexpr const char* kNoCcx =
    "CalculiX (ccx) is not installed: the FEM cross-check did NOT run; install calculix-ccx";

#define SKIP_WITHOUT_CCX()                              \
  do {                                                  \
    if (!calculix_available()) {                        \
      std::fprintf(stderr, "\n*** %s ***\n\n", kNoCcx); \
      GTEST_SKIP() << kNoCcx;                           \
    }                                                   \
  } while (false)

// A fresh directory per test, named after it, removed at the end.
class ScratchDir {
 public:
  ScratchDir() {
    const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
    std::string name = std::string(info->test_suite_name()) + "_" + info->name();
    std::replace_if(
        name.begin(), name.end(), [](char c) { return !std::isalnum(c); }, '_');
    std::random_device random;
    path_ = fs::temp_directory_path() /
            ("phymul_calculix_" + name + "_" + std::to_string(random()) + std::to_string(random()));
    fs::create_directories(path_);
  }
  ~ScratchDir() {
    std::error_code ignored;
    fs::remove_all(path_, ignored);
  }
  ScratchDir(const ScratchDir&) = delete;
  ScratchDir& operator=(const ScratchDir&) = delete;
  fs::path operator/(const std::string& sub) const { return path_ / sub; }

 private:
  fs::path path_;
};

std::vector<std::string> lines_of(const std::string& text) {
  std::vector<std::string> lines;
  std::istringstream in(text);
  for (std::string line; std::getline(in, line);) lines.push_back(line);
  return lines;
}

// The data line right after the first line equal to `card`.
std::string line_after(const std::string& deck, const std::string& card) {
  const std::vector<std::string> lines = lines_of(deck);
  const auto it = std::find(lines.begin(), lines.end(), card);
  return it == lines.end() || it + 1 == lines.end() ? std::string() : *(it + 1);
}

void fix(std::vector<Dirichlet>& bc, const std::vector<int>& nodes, int axis, double value) {
  for (int n : nodes) bc.push_back({n, axis, value});
}

Vec3 total(const std::vector<Vec3>& forces, const std::vector<int>& nodes) {
  Vec3 sum = Vec3::Zero();
  for (int n : nodes) sum += forces[n];
  return sum;
}

double max_norm(const std::vector<Vec3>& v) {
  double m = 0.0;
  for (const Vec3& x : v) m = std::max(m, x.norm());
  return m;
}

// ---- Deck writer and .dat reader: no ccx needed.

TEST(CalculixDeck, NeoHookeanDeckHasTheLawNodesElementsAndBoundaries) {
  const Mesh mesh = make_box({0.02, 0.02, 0.02}, {2, 2, 2}, CellType::hexa);
  std::vector<Dirichlet> bc;
  fix(bc, mesh.node_sets.at("bottom"), 2, 0.0);
  bc.push_back({26, 2, -0.001});
  const Material material{Law::neo_hookean, 14.9e3, 0.499};
  const std::string deck = calculix_deck(mesh, material, bc, 8);

  EXPECT_NE(deck.find("*NODE, NSET=NALL\n1, -0.01, -0.01, -0.01\n"), std::string::npos);
  EXPECT_NE(deck.find("\n27, 0.01, 0.01, 0.01\n"), std::string::npos);
  // VTK hexa order, 1-based: the first cell of make_box is (0, 1, 4, 3, 9, 10, 13, 12).
  EXPECT_EQ(line_after(deck, "*ELEMENT, TYPE=C3D8I, ELSET=EHEXA"), "1, 1, 2, 5, 4, 10, 11, 14, 13");

  const double mu = 14.9e3 / (2 * 1.499), kappa = 14.9e3 / (3 * (1 - 2 * 0.499));
  double c10 = 0, d1 = 0;
  ASSERT_EQ(
      std::sscanf(line_after(deck, "*HYPERELASTIC, NEO HOOKE").c_str(), "%lf, %lf", &c10, &d1), 2);
  EXPECT_DOUBLE_EQ(c10, mu / 2);
  EXPECT_DOUBLE_EQ(d1, 2 / kappa);
  EXPECT_EQ(deck.find("*ELASTIC"), std::string::npos);

  EXPECT_NE(deck.find("*STEP, NLGEOM"), std::string::npos);
  double first = 0, period = 0, smallest = 0, largest = 0;
  ASSERT_EQ(std::sscanf(line_after(deck, "*STATIC").c_str(), "%lf, %lf, %lf, %lf", &first, &period,
                        &smallest, &largest),
            4);
  EXPECT_EQ(first, 0.125);
  EXPECT_EQ(period, 1.0);
  EXPECT_DOUBLE_EQ(smallest, 1.25e-6);
  EXPECT_EQ(largest, 0.125);
  EXPECT_NE(deck.find("1, 3, 3, 0\n"), std::string::npos);
  EXPECT_NE(deck.find("27, 3, 3, -0.001\n"), std::string::npos);
  EXPECT_NE(deck.find("*NODE PRINT, NSET=NALL\nU\n"), std::string::npos);
  EXPECT_NE(deck.find("*NODE PRINT, NSET=NCONS\nRF\n"), std::string::npos);
  EXPECT_EQ(line_after(deck, "*NSET, NSET=NCONS"), "1, 2, 3, 4, 5, 6, 7, 8");
  EXPECT_EQ(line_after(deck, "*NSET, NSET=TOP"), "19, 20, 21, 22, 23, 24, 25, 26");
  EXPECT_TRUE(deck.ends_with("*END STEP\n"));
}

TEST(CalculixDeck, LinearLawIsElasticWithoutNlgeom) {
  const Mesh mesh = make_box({0.02, 0.02, 0.02}, {1, 1, 1}, CellType::tetra);
  const std::string deck =
      calculix_deck(mesh, Material{Law::linear, 1000.0, 0.3}, {{0, 0, 0.0}}, 1, "C3D8");
  EXPECT_EQ(line_after(deck, "*ELASTIC"), "1000, 0.3");
  EXPECT_EQ(deck.find("NLGEOM"), std::string::npos);
  EXPECT_EQ(deck.find("*HYPERELASTIC"), std::string::npos);
  EXPECT_NE(deck.find("*ELEMENT, TYPE=C3D4, ELSET=ETETRA\n"), std::string::npos);
}

TEST(CalculixDeck, RejectsBadInput) {
  const Mesh mesh = make_box({0.02, 0.02, 0.02}, {1, 1, 1}, CellType::hexa);
  const Material material;
  EXPECT_THROW(calculix_deck(mesh, material, {}, 1, "C3D20R"), std::invalid_argument);
  EXPECT_THROW(calculix_deck(mesh, material, {}, 0), std::invalid_argument);
  EXPECT_THROW(calculix_deck(mesh, material, {{8, 0, 0.0}}, 1), std::invalid_argument);
  EXPECT_THROW(calculix_deck(mesh, material, {{0, 3, 0.0}}, 1), std::invalid_argument);
  EXPECT_THROW(calculix_deck(mesh, material, {{0, 0, 0.0}, {0, 0, 1.0}}, 1), std::invalid_argument);
  EXPECT_THROW(calculix_deck(mesh, material, {{0, 0, NAN}}, 1), std::invalid_argument);
  EXPECT_THROW(calculix_deck(mesh, Material{Law::neo_hookean, 1.0, 0.5}, {}, 1),
               std::invalid_argument);
  EXPECT_THROW(calculix_deck(make_ellipsoid_surface({1, 1, 1}, 0), material, {}, 1),
               std::invalid_argument);
}

TEST(CalculixDat, KeepsTheLastTimeAndReadsFortranExponents) {
  const std::string dat =
      "\n"
      " displacements (vx,vy,vz) for set NALL and time  0.5000000E+00\n\n"
      "         1  1.000000E+00  0.000000E+00  0.000000E+00\n"
      "         2  1.000000E+00  0.000000E+00  0.000000E+00\n\n"
      " forces (fx,fy,fz) for set NCONS and time  0.5000000E+00\n\n"
      "         2  9.000000E+00  0.000000E+00  0.000000E+00\n\n"
      " displacements (vx,vy,vz) for set NALL and time  0.1000000E+01\n\n"
      "         1 -3.000000E-03  1.234567-100  2.500000E+01\n"
      "         2  4.000000E-03 -5.000000E-04  0.000000E+00\n\n"
      " forces (fx,fy,fz) for set NCONS and time  0.1000000E+01\n\n"
      "         1  0.000000E+00  0.000000E+00 -2.500000E+00\n\n"
      " forces (fx,fy,fz) for set NTOP and time  0.1000000E+01\n\n"
      "         2  0.000000E+00  0.000000E+00  2.500000E+00\n";
  const CalculixResult r = parse_calculix_dat(dat);
  ASSERT_TRUE(r.ok) << r.message;
  EXPECT_EQ(r.time, 1.0);
  ASSERT_EQ(r.displacement.size(), 2u);
  EXPECT_EQ(r.displacement[0], Vec3(-3e-3, 1.234567e-100, 25.0));
  EXPECT_EQ(r.displacement[1], Vec3(4e-3, -5e-4, 0.0));
  ASSERT_EQ(r.reaction.size(), 2u);
  EXPECT_EQ(r.reaction[0], Vec3(0, 0, -2.5));
  EXPECT_EQ(r.reaction[1], Vec3(0, 0, 2.5));  // the 9 of time 0.5 is gone
}

TEST(CalculixDat, ReportsMissingOrBrokenTables) {
  EXPECT_FALSE(parse_calculix_dat("").ok);
  const CalculixResult gap = parse_calculix_dat(
      " displacements (vx,vy,vz) for set NALL and time  0.1000000E+01\n\n"
      "         1  0.0E+00  0.0E+00  0.0E+00\n"
      "         3  0.0E+00  0.0E+00  0.0E+00\n");
  EXPECT_FALSE(gap.ok);
  EXPECT_NE(gap.message.find("expected 1..3"), std::string::npos) << gap.message;
  const CalculixResult nan = parse_calculix_dat(
      " displacements (vx,vy,vz) for set NALL and time  0.1000000E+01\n\n"
      "         1  NaN  0.0E+00  0.0E+00\n");
  EXPECT_FALSE(nan.ok);
}

TEST(CalculixRun, ReportsCcxErrorsWithTheLogTail) {
  SKIP_WITHOUT_CCX();
  ScratchDir dir;
  const CalculixResult r = run_calculix("*NODE\n1, 0, 0, 0\n*NOT A KEYWORD\n", dir / "run");
  EXPECT_FALSE(r.ok);
  EXPECT_NE(r.message.find("ccx.log"), std::string::npos) << r.message;
}

// ---- Exact answers (needs ccx): uniform strain is reproduced exactly by every element, so
// the reactions and displacements of a block in uniaxial tension are known in closed form.

struct Uniaxial {
  Mesh mesh;
  std::vector<Dirichlet> bc;
  std::vector<int> top, bottom;
  double length = 0, area = 0;  // along z; reference cross-section (volume / length)
  Vec3 origin;                  // the point that does not move
};

// Roller supports: bottom face z-fixed, the x = min face x-fixed, the y = min face y-fixed
// (a box), or for a cylinder the bottom centre fixed in x, y and the rim node on +x in y.
Uniaxial uniaxial(Mesh mesh, double stretch) {
  Uniaxial u;
  u.top = mesh.node_sets.at("top");
  u.bottom = mesh.node_sets.at("bottom");
  Vec3 lo = mesh.points[0], hi = mesh.points[0];
  for (const Vec3& p : mesh.points) {
    lo = lo.cwiseMin(p);
    hi = hi.cwiseMax(p);
  }
  u.length = hi.z() - lo.z();
  double volume = 0;
  for (const Cell& c : mesh.cells) volume += cell_measure(mesh.points, c);
  u.area = volume / u.length;
  fix(u.bc, u.bottom, 2, 0.0);
  fix(u.bc, u.top, 2, (stretch - 1.0) * u.length);
  if (mesh.node_sets.contains("left")) {
    fix(u.bc, mesh.node_sets.at("left"), 0, 0.0);
    fix(u.bc, mesh.node_sets.at("front"), 1, 0.0);
    u.origin = lo;
  } else {  // make_cylinder_volume: node 0 is the bottom centre, node 1 the rim node on +x
    u.bc.push_back({0, 0, 0.0});
    u.bc.push_back({0, 1, 0.0});
    u.bc.push_back({1, 1, 0.0});
    u.origin = mesh.points[0];
  }
  u.mesh = std::move(mesh);
  return u;
}

void expect_linear_uniaxial(Mesh mesh, const std::string& element) {
  SCOPED_TRACE(element);
  const double young = 14.9e3, nu = 0.3, strain = 1e-3;
  const Uniaxial u = uniaxial(std::move(mesh), 1.0 + strain);
  ScratchDir dir;
  const CalculixResult r = run_calculix(
      calculix_deck(u.mesh, Material{Law::linear, young, nu}, u.bc, 1, element), dir / "run");
  ASSERT_TRUE(r.ok) << r.message;
  ASSERT_EQ(r.displacement.size(), u.mesh.points.size());

  const double force = young * u.area * strain;
  EXPECT_NEAR(total(r.reaction, u.top).z(), force, 1e-4 * force);
  EXPECT_NEAR(total(r.reaction, u.bottom).z(), -force, 1e-4 * force);
  const double scale = strain * u.length;
  for (std::size_t i = 0; i < u.mesh.points.size(); ++i) {
    const Vec3 d = u.mesh.points[i] - u.origin;
    const Vec3 exact(-nu * strain * d.x(), -nu * strain * d.y(), strain * d.z());
    ASSERT_LT((r.displacement[i] - exact).norm(), 1e-5 * scale) << "node " << i;
  }
}

TEST(CalculixExact, LinearUniaxialHexaBlockC3D8I) {
  SKIP_WITHOUT_CCX();
  expect_linear_uniaxial(
      make_box({0.03, 0.02, 0.05}, {3, 2, 4}, CellType::hexa, {0.01, -0.02, 0.03}), "C3D8I");
}

TEST(CalculixExact, LinearUniaxialTetraBlockAndWedgeCylinder) {
  SKIP_WITHOUT_CCX();
  expect_linear_uniaxial(make_box({0.03, 0.02, 0.05}, {2, 2, 3}, CellType::tetra), "C3D8I");
  expect_linear_uniaxial(make_cylinder_volume(0.01, 0.03, 12, 3, 2), "C3D8I");
}

// Neo-Hookean block stretched homogeneously by lambda along z, free laterally: the lateral
// stretch t makes the lateral Cauchy stress vanish,
//   sigma_lat = mu/3 J^(-5/3) (t^2 - lambda^2) + K (J - 1) = 0,  J = lambda t^2,
// and the axial force is sigma_zz * (current area) = sigma_zz * A0 t^2 with
//   sigma_zz = 2 mu/3 J^(-5/3) (lambda^2 - t^2) + K (J - 1).
// Matching it proves that C10 = mu/2, D1 = 2/K reproduce phymul's W = mu/2 (I1bar - 3) +
// K/2 (J - 1)^2 in CalculiX, at finite strain.
TEST(CalculixExact, NeoHookeanUniaxialStretchMatchesClosedForm) {
  SKIP_WITHOUT_CCX();
  const double young = 14.9e3, nu = 0.45, lambda = 0.8;
  const double mu = young / (2 * (1 + nu)), kappa = young / (3 * (1 - 2 * nu));
  const auto lateral = [&](double t) {
    const double j = lambda * t * t;
    return mu / 3 * std::pow(j, -5.0 / 3) * (t * t - lambda * lambda) + kappa * (j - 1);
  };
  double lo = 0.5, hi = 2.0;  // lateral(lo) < 0 < lateral(hi)
  for (int i = 0; i < 200; ++i) (lateral(0.5 * (lo + hi)) < 0 ? lo : hi) = 0.5 * (lo + hi);
  const double t = 0.5 * (lo + hi), j = lambda * t * t;
  const double sigma =
      2 * mu / 3 * std::pow(j, -5.0 / 3) * (lambda * lambda - t * t) + kappa * (j - 1);

  const Uniaxial u = uniaxial(make_box({0.03, 0.02, 0.05}, {3, 2, 4}, CellType::hexa), lambda);
  ScratchDir dir;
  const CalculixResult r = run_calculix(
      calculix_deck(u.mesh, Material{Law::neo_hookean, young, nu}, u.bc, 5), dir / "run");
  ASSERT_TRUE(r.ok) << r.message;
  EXPECT_DOUBLE_EQ(r.time, 1.0);
  const double force = sigma * u.area * t * t;
  EXPECT_NEAR(total(r.reaction, u.top).z(), force, 1e-4 * std::abs(force));
  for (std::size_t i = 0; i < u.mesh.points.size(); ++i) {
    const Vec3 d = u.mesh.points[i] - u.origin;
    const Vec3 exact((t - 1) * d.x(), (t - 1) * d.y(), (lambda - 1) * d.z());
    ASSERT_LT((r.displacement[i] - exact).norm(), 1e-5 * u.length) << "node " << i;
  }
}

// ---- The cross-check (DESIGN 5): bonded 80 mm cube of soft tissue, 8 x 8 x 8 hexahedra,
// base fixed, the top plate pushed down towards it without slip. CalculiX (C3D8I, NEO HOOKE,
// NLGEOM) against phymul::fem::solve_static on the same mesh and loads, with both of our
// hexahedra.
//
// Our incompatible-mode hexahedron is the same element as C3D8I on this mesh (cubes), so the
// two codes discretise the same energy and every node must agree to 1 % of the plate travel
// (the criterion; measured: below 1e-4 %), the plate force to 3 % (measured: below
// 1e-4 %).
//
// Our default, mean-dilatation hexahedron is another element technology against locking at
// nu = 0.499, and the solution is singular along the edges where the bonded faces meet the
// free sides. There the two 8^3 solutions differ by 2.6 to 3.5 % of the plate travel, while
// each is 7 to 8 % away from its own 16^3 solution, and the two 16^3 solutions agree to
// 1.35 % (4 mm push; RMS 0.2 %, top force 0.6 %): a discretisation difference that shrinks
// with the mesh, not a modelling one. So for it every node must agree within 5 %, the RMS
// over the nodes within 1 % (0.6 % measured), and the plate force within 3 % (1.1 to 1.7 %).
struct Tolerance {
  double node_max, node_rms, force;  // of max |u|, of max |u|, relative
};
constexpr Tolerance kSameElement{0.01, 0.01, 0.03};
constexpr Tolerance kMeanDilatation{0.05, 0.01, 0.03};

void compare_with_ccx(const Mesh& mesh, const CalculixResult& ccx, const Problem& problem,
                      const Tolerance& tolerance, const char* name) {
  SCOPED_TRACE(name);
  const auto start = std::chrono::steady_clock::now();
  const Result ours = solve_static(problem);
  const double seconds_ours =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  ASSERT_TRUE(ours.converged) << ours.message;
  ASSERT_EQ(ours.displacement.size(), mesh.points.size());
  ASSERT_EQ(ours.reaction.size(), mesh.points.size());

  double largest = 0.0, squares = 0.0;
  std::size_t where = 0;
  for (std::size_t i = 0; i < mesh.points.size(); ++i) {
    const double d = (ccx.displacement[i] - ours.displacement[i]).norm();
    squares += d * d;
    if (d > largest) {
      largest = d;
      where = i;
    }
  }
  const std::vector<int>& top = mesh.node_sets.at("top");
  const double u_ccx = max_norm(ccx.displacement), u_ours = max_norm(ours.displacement);
  const double rms = std::sqrt(squares / double(mesh.points.size()));
  const double f_ccx = total(ccx.reaction, top).z(), f_ours = total(ours.reaction, top).z();
  const Vec3 at = 1e3 * mesh.points[where];
  std::printf(
      "%-16s %7.1f %10.4f %11.4f %9.5f%% %9.5f%% %11.4f %12.4f %9.5f%% %7.2f %7.2f  (%g, %g, %g)\n",
      name, -problem.prescribed.back().value * 1e3, u_ccx * 1e3, u_ours * 1e3,
      100 * largest / u_ccx, 100 * rms / u_ccx, f_ccx, f_ours,
      100 * (f_ours - f_ccx) / std::abs(f_ccx), ccx.wall_seconds, seconds_ours, at.x(), at.y(),
      at.z());
  std::fflush(stdout);
  EXPECT_LT(rms, tolerance.node_rms * u_ccx) << "RMS node displacement difference";
  EXPECT_LT(largest, tolerance.node_max * u_ccx) << "largest node displacement difference";
  EXPECT_NEAR(f_ours, f_ccx, tolerance.force * std::abs(f_ccx)) << "total top reaction (N)";
}

TEST(CalculixCrossCheck, BondedCubeCompressionAgreesWithReferenceFem) {
  SKIP_WITHOUT_CCX();
  const Material material{Law::neo_hookean, 14.9e3, 0.499};
  const Mesh mesh = make_box({0.08, 0.08, 0.08}, {8, 8, 8}, CellType::hexa, {0.0, 0.0, 0.04});
  const std::vector<int>& top = mesh.node_sets.at("top");
  const std::vector<int>& bottom = mesh.node_sets.at("bottom");

  std::printf(
      "\nBonded 80 mm cube, 8x8x8 hexa, E = 14.9 kPa, nu = 0.499, Neo-Hooke "
      "(W = mu/2 (I1bar - 3) + K/2 (J - 1)^2):\nCalculiX 2.20 C3D8I NLGEOM vs "
      "phymul::fem::solve_static; node differences over max |u|\n");
  std::printf("%-16s %7s %10s %11s %10s %10s %11s %12s %10s %7s %7s  %s\n", "our hexahedron",
              "push mm", "max|u|ccx", "max|u|ours", "max diff", "rms diff", "F_top ccx",
              "F_top ours", "F diff", "ccx s", "ours s", "largest difference at (mm)");
  for (const double level : {0.004, 0.010, 0.0146}) {
    SCOPED_TRACE("plate pushed " + std::to_string(level * 1e3) + " mm");
    const int steps = int(std::ceil(level / 0.001));  // about 1 mm per load step
    std::vector<Dirichlet> bc;
    for (int axis = 0; axis < 3; ++axis) fix(bc, bottom, axis, 0.0);
    fix(bc, top, 0, 0.0);
    fix(bc, top, 1, 0.0);
    fix(bc, top, 2, -level);

    ScratchDir dir;
    const CalculixResult ccx =
        run_calculix(calculix_deck(mesh, material, bc, steps, "C3D8I"), dir / "ccx");
    ASSERT_TRUE(ccx.ok) << ccx.message;
    ASSERT_DOUBLE_EQ(ccx.time, 1.0);
    ASSERT_EQ(ccx.displacement.size(), mesh.points.size());
    EXPECT_NEAR(ccx.displacement[top[0]].z(), -level, 1e-6 * level);  // the plate got there
    EXPECT_LT(total(ccx.reaction, top).z(), 0.0);  // pushing down: the plate pushes down
    // The base carries what the plate applies.
    EXPECT_NEAR(total(ccx.reaction, bottom).z(), -total(ccx.reaction, top).z(),
                1e-3 * std::abs(total(ccx.reaction, top).z()));

    Problem problem;
    problem.mesh = mesh;
    problem.material = material;
    problem.prescribed = bc;
    problem.load_steps = steps;
    compare_with_ccx(mesh, ccx, problem, kMeanDilatation, "mean dilatation");
    problem.material.hexa = HexaElement::incompatible_modes;
    compare_with_ccx(mesh, ccx, problem, kSameElement, "incompatible");
  }
}

}  // namespace
}  // namespace phymul::fem
