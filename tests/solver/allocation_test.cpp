// No heap allocation inside a step: operator new and, with glibc, malloc and its kin count
// while steps run.
#include <gtest/gtest.h>
#include <omp.h>

#include <atomic>
#include <cerrno>
#include <cstdlib>
#include <filesystem>
#include <new>
#include <utility>
#include <vector>

#include "phymul/scene_io.hpp"
#include "phymul/simulation.hpp"
#include "support/models.hpp"
#include "support/process.hpp"

// AddressSanitizer brings its own operator new; replacing it there mixes allocators.
// (GCC says so by __SANITIZE_ADDRESS__, clang by __has_feature.)
#if defined(__has_feature)
#if __has_feature(address_sanitizer)
#define PHYMUL_ASAN 1
#endif
#endif
#if defined(__SANITIZE_ADDRESS__) || defined(PHYMUL_ASAN)
#define PHYMUL_COUNT_ALLOCATIONS 0
#else
#define PHYMUL_COUNT_ALLOCATIONS 1
#endif

namespace {
std::atomic<long> allocations{0};
std::atomic<bool> counting{false};
}  // namespace

#if PHYMUL_COUNT_ALLOCATIONS
// The replacement pairs malloc with free by design; GCC 12, inlining it into a vector's
// allocation, sees malloc-from-new freed by delete and warns (-Wmismatched-new-delete).
#pragma GCC diagnostic ignored "-Wmismatched-new-delete"
void* operator new(std::size_t size) {
  if (counting) ++allocations;
  if (void* p = std::malloc(size ? size : 1)) return p;
  throw std::bad_alloc();
}
void operator delete(void* p) noexcept { std::free(p); }
void operator delete(void* p, std::size_t) noexcept { std::free(p); }
#endif

// C allocations too (the OpenMP runtime's, fmt's), where glibc lets this binary's malloc stand
// in for its own (operator new above, through std::malloc, is then counted twice: the tests
// ask for none).
namespace {
std::atomic<long> c_allocations{0};
}
#if PHYMUL_COUNT_ALLOCATIONS && defined(__GLIBC__)
#define PHYMUL_COUNT_C_ALLOCATIONS 1
extern "C" {
void* __libc_malloc(std::size_t);
void* __libc_calloc(std::size_t, std::size_t);
void* __libc_realloc(void*, std::size_t);
void* __libc_memalign(std::size_t, std::size_t);
void* malloc(std::size_t size) {
  if (counting) ++c_allocations;
  return __libc_malloc(size);
}
void* calloc(std::size_t n, std::size_t size) {
  if (counting) ++c_allocations;
  return __libc_calloc(n, size);
}
void* realloc(void* p, std::size_t size) {
  if (counting) ++c_allocations;
  return __libc_realloc(p, size);
}
void* aligned_alloc(std::size_t alignment, std::size_t size) {
  if (counting) ++c_allocations;
  return __libc_memalign(alignment, size);
}
int posix_memalign(void** p, std::size_t alignment, std::size_t size) {
  if (counting) ++c_allocations;
  *p = __libc_memalign(alignment, size);
  return *p ? 0 : ENOMEM;
}
// libgomp's teams come from here (its gomp_aligned_alloc, as Debian builds it).
void* memalign(std::size_t alignment, std::size_t size) {
  if (counting) ++c_allocations;
  return __libc_memalign(alignment, size);
}
}
#else
#define PHYMUL_COUNT_C_ALLOCATIONS 0
#endif

namespace phymul {
namespace {

// Heap allocations during 50 steps and a residual check, after a first step (which may size
// what it needs); with the residual, which shows the steps had work to do.
std::pair<long, double> allocations_in_steps(Simulator& sim) {
  sim.step();
  allocations = 0;
  c_allocations = 0;
  counting = true;
  for (int k = 0; k < 50; ++k) sim.step();
  const double residual = sim.max_residual_force();
  counting = false;
  return {allocations.load() + c_allocations.load(), residual};
}

TEST(Simulator, StepsDoNotAllocate) {
  if (!PHYMUL_COUNT_ALLOCATIONS)
    GTEST_SKIP() << "allocations are counted in the normal build only (AddressSanitizer owns "
                    "operator new here)";
  // (The implicit steps factorise their matrix in the first step, before the count.)
  for (Integrator integrator :
       {Integrator::verlet, Integrator::newton_cotes, Integrator::implicit}) {
    Model model;
    const int c = add_elastic_component(model, "block",
                                        make_box(Vec3(0.03, 0.03, 0.03), {4, 4, 4}, CellType::hexa),
                                        testing::material(20.0));
    add_volume_constraint(model, c);
    add_fixed_nodes(model, model.components[c].node_sets.at("bottom"));
    add_applied_force(model, {model.components[c].node_sets.at("top"),
                              Schedule{{0.0, 0.01}, {Vec3::Zero(), Vec3(0, 0, -1e-3)}}});
    model.gravity = Vec3(0, 0, -9.81);
    model.settings.integrator = integrator;
    finalize(model);
    Simulator sim(model);
    const auto [count, residual] = allocations_in_steps(sim);
    EXPECT_EQ(count, 0);
    EXPECT_GT(residual, 0.0);
  }
}

// Rigid bodies, doubled nodes, stitched nodes and fibres: the organ examples step without
// allocating too.
TEST(Simulator, OrganExampleStepsDoNotAllocate) {
  if (!PHYMUL_COUNT_ALLOCATIONS) GTEST_SKIP() << "allocations are counted in the normal build only";
  const std::filesystem::path examples = testing::source_dir() / "examples";
  for (const char* name : {"muscle.yaml", "fig1c_ligament.yaml", "fig1b_doubled_nodes.yaml"}) {
    for (Integrator integrator : {Integrator::verlet, Integrator::newton_cotes}) {
      Model model = compile_scene(load_scene(examples / name));
      model.settings.integrator = integrator;
      Simulator sim(model);
      const auto [count, residual] = allocations_in_steps(sim);
      EXPECT_EQ(count, 0) << name;
      EXPECT_GT(residual, 0.0);
    }
  }
}

// Implicit steps against an obstacle, smooth or rough: the contacts' columns of P^-1, their
// Schur complement and the friction's state live in storage sized when the matrix is
// factorised.
TEST(Simulator, ImplicitStepsAgainstAnObstacleDoNotAllocate) {
  if (!PHYMUL_COUNT_ALLOCATIONS) GTEST_SKIP() << "allocations are counted in the normal build only";
  for (double friction : {0.0, 0.5}) {
    SCOPED_TRACE(friction);
    Scene scene = load_scene(testing::source_dir() / "examples" / "bladder_filling.yaml");
    scene.simulation.integrator = Integrator::implicit;
    scene.obstacles.at(0).position.z() = -0.029;  // the floor under the bladder's bottom at once
    scene.obstacles.at(0).friction = friction;
    scene.objects.at(0).mesh.subdivisions = 2;  // 162 nodes
    Simulator sim(compile_scene(scene));
    sim.set_dt(10.0 * sim.dt());
    while (sim.data().contact_force.at(0).norm() == 0.0) sim.step();  // on the floor
    const auto [count, residual] = allocations_in_steps(sim);
    EXPECT_EQ(count, 0);
    EXPECT_GT(sim.data().contact_force[0].z(), 0.0);
  }
}

// The muscle example (fibres, a free and a held rigid body, doubled nodes, a volume): its
// implicit steps through the activation move the bodies in place.
TEST(Simulator, ImplicitStepsWithBodiesAndFibresDoNotAllocate) {
  if (!PHYMUL_COUNT_ALLOCATIONS) GTEST_SKIP() << "allocations are counted in the normal build only";
  Scene scene = load_scene(testing::source_dir() / "examples" / "muscle.yaml");
  scene.simulation.integrator = Integrator::implicit;
  Simulator sim(compile_scene(scene));
  sim.set_dt(10.0 * sim.dt());
  while (sim.data().time < 1.0) sim.step();  // half active
  const auto [count, residual] = allocations_in_steps(sim);
  EXPECT_EQ(count, 0);
  EXPECT_GT(residual, 0.0);
}

// Finite elements bending under their weight (the cantilever of fem_newton_cantilever.yaml,
// with a volume kept so that the rest gradients' solves are redone too): the steps
// refactorise P as the cells turn, in place.
TEST(Simulator, ImplicitStepsRefactorisingTurnedCellsDoNotAllocate) {
  if (!PHYMUL_COUNT_ALLOCATIONS) GTEST_SKIP() << "allocations are counted in the normal build only";
  Scene scene = load_scene(testing::source_dir() / "examples" / "fem_newton_cantilever.yaml");
  scene.simulation.mode = SolveMode::dynamic;
  scene.simulation.integrator = Integrator::implicit;
  scene.simulation.damping = 10.0;
  scene.objects.at(0).volume_constraint = true;
  Simulator sim(compile_scene(scene));
  sim.set_dt(5e-3);
  const std::vector<Eigen::Quaterniond> before = sim.data().cell_rotation;
  const auto [count, residual] = allocations_in_steps(sim);
  EXPECT_EQ(count, 0);
  EXPECT_GT(residual, 0.0);
  int turned = 0;  // cells whose rotation P took anew during the count
  for (size_t c = 0; c < before.size(); ++c)
    turned += sim.data().cell_rotation[c].angularDistance(before[c]) > 0.0;
  EXPECT_GT(turned, 0);
}

// Two balls pressed together (examples/two_balls.yaml): the contact pair's rows, their fit
// and the projection after each solve work in preallocated storage.
TEST(Simulator, ImplicitStepsWithAContactPairDoNotAllocate) {
  if (!PHYMUL_COUNT_ALLOCATIONS) GTEST_SKIP() << "allocations are counted in the normal build only";
  Scene scene = load_scene(testing::source_dir() / "examples" / "two_balls.yaml");
  scene.simulation.integrator = Integrator::implicit;
  Simulator sim(compile_scene(scene));
  sim.set_dt(10.0 * sim.dt());
  for (int k = 0; k < 2000 && sim.data().pair_contact_force[0].norm() == 0.0; ++k) sim.step();
  ASSERT_GT(sim.data().pair_contact_force[0].norm(), 0.0);  // touching
  const auto [count, residual] = allocations_in_steps(sim);
  EXPECT_EQ(count, 0);
  EXPECT_GT(residual, 0.0);
  EXPECT_GT(sim.data().pair_contact_force[0].norm(), 0.0);
}

// Surfaces sharing nodes (a prostate stitched to a bladder): the joint volume projection,
// velocity projection and residual's pressures work in preallocated storage.
TEST(Simulator, CoupledVolumeStepsDoNotAllocate) {
  if (!PHYMUL_COUNT_ALLOCATIONS) GTEST_SKIP() << "allocations are counted in the normal build only";
  const std::filesystem::path scene = testing::source_dir() / "bench" / "coupled_volumes.yaml";
  for (Integrator integrator :
       {Integrator::verlet, Integrator::newton_cotes, Integrator::implicit}) {
    Model model = compile_scene(load_scene(scene));
    ASSERT_TRUE(model.coupled_volumes);
    model.settings.integrator = integrator;
    Simulator sim(model);
    const auto [count, residual] = allocations_in_steps(sim);
    EXPECT_EQ(count, 0);
    EXPECT_GT(residual, 0.0);
  }
}

// The environment's interactions too: pressure, a moving rough probe, two coupled volumes
// (a balloon) and a deformable contact (spatial hash rebuilt every step).
TEST(Simulator, StepsWithInteractionsDoNotAllocate) {
  if (!PHYMUL_COUNT_ALLOCATIONS) GTEST_SKIP() << "allocations are counted in the normal build only";
  Model model;
  const int block = add_elastic_component(
      model, "block", make_box(Vec3(0.03, 0.03, 0.02), {4, 4, 3}, CellType::hexa),
      testing::material(20.0));
  const int ball = add_elastic_component(
      model, "ball", make_ellipsoid_volume({0.01, 0.01, 0.01}, 1, 2, Vec3(0, 0, 0.0205)),
      testing::material(20.0));
  add_volume_constraint(model, block);
  add_volume_constraint(model, ball);
  add_fixed_nodes(model, model.components[block].node_sets.at("bottom"));
  add_pressure(model, {ball, model.components[ball].boundary,
                       Schedule{{0.0, 0.01}, {Vec3::Zero(), Vec3(500, 0, 0)}}});
  RigidObstacle probe;
  probe.shape = RigidObstacle::Shape::probe;
  probe.point = Vec3(0, 0, 0.04);
  probe.axis = -Vec3::UnitZ();
  probe.radius = 0.004;
  probe.friction = 0.3;
  probe.motion = Schedule{{0.0, 0.05}, {Vec3::Zero(), Vec3(0, 0, -0.01)}};
  add_rigid_obstacle(model, probe);
  add_contact_pair(model, block, ball);
  model.gravity = Vec3(0, 0, -9.81);
  model.volumes[1].target_schedule = Schedule{{0.0, 0.05},
                                              {Vec3(model.volumes[1].target_volume, 0, 0),
                                               Vec3(1.2 * model.volumes[1].target_volume, 0, 0)}};
  finalize(model);
  Simulator sim(model);
  const auto [count, residual] = allocations_in_steps(sim);
  EXPECT_EQ(count, 0);
  EXPECT_GT(residual, 0.0);
}

// Large enough for every loop's thread team (15,625 nodes), on two threads and on one: neither
// the steps nor the OpenMP runtime under them allocate, C allocations counted too. (GCC's
// libgomp allocates a team of one thread every time it opens one: such loops run without.)
TEST(Simulator, ParallelStepsDoNotAllocateInTheThreadRuntimeEither) {
  if (!PHYMUL_COUNT_C_ALLOCATIONS)
    GTEST_SKIP() << "C allocations are counted with glibc in the normal build only";
  Model model;
  const int c = add_elastic_component(
      model, "block", make_box(Vec3(0.08, 0.08, 0.08), {24, 24, 24}, CellType::hexa),
      testing::material(100.0));
  add_volume_constraint(model, c);
  add_fixed_nodes(model, model.components[c].node_sets.at("bottom"));
  model.gravity = Vec3(0, 0, -9.81);
  finalize(model);
  const int threads = omp_get_max_threads();
  for (int team : {2, 1}) {
    omp_set_num_threads(team);
    Simulator sim(model);
    const auto [count, residual] = allocations_in_steps(sim);
    EXPECT_EQ(count, 0) << team << " threads";
    EXPECT_GT(residual, 0.0);
  }
  omp_set_num_threads(threads);
}

// The prostate study's scene on one thread, as its benchmark and real-time figure run it.
TEST(Simulator, ProstateStudyStepsDoNotAllocateOnOneThread) {
  if (!PHYMUL_COUNT_C_ALLOCATIONS)
    GTEST_SKIP() << "C allocations are counted with glibc in the normal build only";
  const std::filesystem::path scene =
      testing::source_dir() / "examples" / "prostate" / "50mL_rigid.yaml";
  const int threads = omp_get_max_threads();
  omp_set_num_threads(1);
  Simulator sim(compile_scene(load_scene(scene)));
  const auto [count, residual] = allocations_in_steps(sim);
  omp_set_num_threads(threads);
  EXPECT_EQ(count, 0);
  EXPECT_GT(residual, 0.0);
}

}  // namespace
}  // namespace phymul

namespace phymul {
namespace {

// A needle through the pressing, the puncture and the track's growth: its track and events
// live in storage reserved when the Data was made; in implicit steps (2 ms) its rows and
// sliding states too, sized with the matrix.
TEST(Simulator, NeedleStepsDoNotAllocate) {
  if (!PHYMUL_COUNT_ALLOCATIONS) GTEST_SKIP() << "allocations are counted in the normal build only";
  for (const bool implicit : {false, true}) {
    SCOPED_TRACE(implicit);
    Scene scene = load_scene(testing::source_dir() / "examples/prostate/biopsy.yaml");
    if (implicit) scene.simulation.integrator = Integrator::implicit, scene.simulation.dt = 2e-3;
    Simulator sim(compile_scene(scene));
    while (sim.data().time < 0.9) sim.step();  // the tip presses the gland from 0.66 s on
    allocations = 0;
    c_allocations = 0;
    counting = true;
    while (sim.data().time < 1.4) sim.step();
    counting = false;
    EXPECT_EQ(allocations.load() + c_allocations.load(), 0);
    EXPECT_EQ(sim.data().needles[0].punctures.size(), 1u);
    EXPECT_GE(sim.data().needles[0].track.size(), 3u);
  }
}

}  // namespace
}  // namespace phymul
