// Data: everything a run changes (MuJoCo's mjData beside mjModel). A step reads a const
// Model and one Data and writes that Data only, so one compiled Model drives any number of
// Data at once (threads, sweeps). A checkpoint is a Data, saved and restored whole.
#pragma once

#include <Eigen/Geometry>
#include <memory>
#include <vector>

#include "phymul/model.hpp"

namespace phymul {

// Pose and momenta of a rigid body.
struct RigidBodyState {
  Vec3 center = Vec3::Zero();                  // m, centre of mass
  Eigen::Quaterniond orientation{1, 0, 0, 0};  // principal frame -> world
  Vec3 momentum = Vec3::Zero();                // kg m/s
  Vec3 angular_momentum = Vec3::Zero();        // kg m^2/s, about the centre, world frame
};

// A node put back on the other side's surface of a contact pair by a step's contact stage:
// what the velocity stage and a static residual read.
struct PairContact {
  int pair = 0, side = 0;  // the node belongs to component pair.components[side]
  int node = 0;
  Triangle triangle{};          // of the other side, global ids
  Vec3 weights = Vec3::Zero();  // barycentric weights of the contact point
  Vec3 normal = Vec3::UnitZ();  // unit, out of the other side
  double impulse = 0.0;         // N s along normal on the node (minus it on the triangle)
};

// A point of a tissue held on a needle's shaft (Needle): laterally on the axis, and along it
// at `anchor` while it sticks.
struct TrackPoint {
  int tissue = 0;  // index in Needle::tissues
  EmbeddedPoint point;
  double anchor = 0.0;  // m along the shaft from the tip (<= 0 behind it): where it sticks
  double length = 0.0;  // m of track it stands for: its share of the friction
};

// A needle's tip pushed through a tissue's surface.
struct PunctureEvent {
  int tissue = 0;      // index in Needle::tissues
  double time = 0.0;   // s
  double depth = 0.0;  // m
  double force = 0.0;  // N, the tip's push along the shaft that broke through
};

// Where a tissue stands with a needle: untouched, pressed by the tip, punctured (an int in
// NeedleState, as checkpoints store plain numbers).
enum NeedlePhase : int { needle_outside = 0, needle_pressed = 1, needle_punctured = 2 };

// What a needle has done to the tissues so far (Needle).
struct NeedleState {
  std::vector<int> phase;                // per tissue: a NeedlePhase
  TrackPoint contact;                    // the surface point the tip presses (a tissue `pressed`)
  std::vector<TrackPoint> track;         // by insertion; at most Needle::track_capacity (reserved)
  double depth = 0.0;                    // m, of the tip at the last step
  double last_point_depth = 0.0;         // m, of the tip when the last track point was made
  int tip_tissue = -1;                   // the punctured tissue the tip advances in, or -1
  Vec3 force = Vec3::Zero();             // N, of the tissues on the needle over the last step
  std::vector<PunctureEvent> punctures;  // at most kMaxPunctures (reserved)
};

// Puncture events a needle records (later ones are not).
inline constexpr size_t kMaxPunctures = 64;

// Where a static solve stands between two relaxation iterations: with the rest of Data, all
// that its next iteration reads.
struct StaticProgress {
  int load_step = 0;              // the load step under way, 1-based; 0 before the first
  long iterations = 0;            // in the load steps before it
  long step_iterations = 0;       // in the load step under way
  double previous_kinetic = 0.0;  // J, the kinetic damping's last peak candidate
  double fire_alpha = 0.1;        // FIRE: share of the force direction mixed into velocities
  long fire_downhill = 0;         // FIRE: steps since its last restart
};

// The implicit steps' Anderson history (solver/implicit_anderson.hpp), carried from one step
// to the next without friction: the differences of the fixed-point residuals (df) and of the
// images (dg) between consecutive iterations, `count` columns of a value per node in a ring
// whose newest is at `newest`, and df's dot products (gram, column by column). It holds for
// the step h, share alpha and held set `held` (a signature) it was taken with, and is dropped
// under others. Empty where the acceleration does not apply.
struct AndersonHistory {
  double h = 0.0;              // s
  double alpha = 1.0;          // the share of its corrections the iterations took
  long held = -1;              // which nodes the solves held on obstacles; -1: none yet
  int count = 0, newest = -1;  // columns held, the newest's place
  std::vector<Vec3> df, dg;    // column k's node i at k n + i
  std::vector<double> gram;    // df_j . df_k at j depth + k
};

// Buffers a step works in and caches keyed on the positions they were computed at: sized
// from the model when the Data is made, so that a step allocates nothing, and never read
// across steps but through their keys (a fresh one gives the same results). Internal.
struct Workspace;

namespace detail {
// Owns a T on the heap and copies it deeply: keeps an internal type out of the public
// headers while the Data that holds it copies as a value.
template <class T>
class Owned {
 public:
  Owned();
  ~Owned();
  Owned(const Owned& other);
  Owned(Owned&& other) noexcept;
  Owned& operator=(const Owned& other);
  Owned& operator=(Owned&& other) noexcept;
  T& operator*() const { return *p_; }
  T* operator->() const { return p_.get(); }

 private:
  std::unique_ptr<T> p_;
};
}  // namespace detail

// The inputs a program may steer between steps (a controller: the Python module, a live
// view): made from the model's schedules by allocate_data, and read by every step from here,
// so that setting one changes this Data's run only.
struct Controls {
  std::vector<Vec3> applied_force;         // N per node, added to the loads; empty: none
  std::vector<Schedule> obstacle_motion;   // per obstacle: translation of its shape, m
  std::vector<Schedule> pressure;          // per pressure load: Pa in x
  std::vector<Schedule> target_volume;     // per volume constraint: m^3 in x; empty: rest volume
  std::vector<Schedule> body_translation;  // per rigid body (driven ones follow it): m
  std::vector<Schedule> body_rotation;     // per rigid body: rad, a rotation vector
  std::vector<Schedule> needle_depth;      // per needle: m in x
};

// A volume constraint's target (m^3) at load_time under these controls.
inline double target_volume(const Model& model, const Controls& controls, size_t k,
                            double load_time) {
  const Schedule& s = controls.target_volume[k];
  return s.empty() ? model.volumes[k].target_volume : s.at(load_time).x();
}

struct Data {
  double time = 0.0;       // s
  long step = 0;           // steps taken (dynamics) or relaxation iterations (statics)
  std::vector<Vec3> x, v;  // m, m/s, per node
  std::vector<Vec3> f;     // N, every force but damping, at (x, load_time)
  // m/s^2 per node with the implicit integrator (else empty): the last step's mean acceleration
  // (v - v at its start) / dt, which the next step's first guess continues.
  std::vector<Vec3> acceleration;
  std::vector<Eigen::Quaterniond> rotation;  // per shape-memory node: last best-fit rotation
  // Per explicit finite-element cell (the objects' in order), with the implicit integrator or
  // static solver (else empty): its deformation's rotation where the implicit step's matrix
  // last took the cells' stiffness, turned with them (identity at first).
  std::vector<Eigen::Quaterniond> cell_rotation;
  // J: elastic energy at the last force pass (shape memory and explicit finite elements).
  double shape_memory_energy = 0.0;

  std::vector<RigidBodyState> bodies;  // per Model::rigid_bodies
  // N, per rigid obstacle: the force it exerted on the body over the last step (its impulse
  // over dt; zero before the first step).
  std::vector<Vec3> contact_force;
  // N, per contact pair: the force the second component exerted on the first over the last
  // step.
  std::vector<Vec3> pair_contact_force;
  // Per node: the obstacle whose contact stage last moved it in the last step, or -1 (empty
  // without obstacles): a node the volume projection then moved off by a hair still touches.
  std::vector<int> obstacle_touching;
  // The contact pairs' contacts of the last step, at most pair_contact_capacity(model) (so
  // much is reserved: a step allocates nothing).
  std::vector<PairContact> pair_contacts;
  std::vector<NeedleState> needles;  // per Model::needles
  AndersonHistory anderson;          // with the implicit integrator

  double dt = 0.0;         // s, the explicit step
  double stable_dt = 0.0;  // s, the stability estimate `dt: auto` takes its share of
  double load_time = 0.0;  // s, the load time at which f was evaluated
  StaticProgress static_progress;
  Controls controls;

  detail::Owned<Workspace> work;  // not saved: see Workspace
};

// The most contacts one step's contact-pair stage records.
size_t pair_contact_capacity(const Model& model);

// A Data for the model with every array sized and the nodes at rest, time 0, forces zero,
// dt 0 (make_data, simulation.hpp, also poses, constrains, evaluates and picks dt).
Data allocate_data(const Model& model);

}  // namespace phymul
