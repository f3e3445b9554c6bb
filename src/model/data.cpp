#include <fmt/format.h>

#include <limits>

#include "model/data_fields.hpp"
#include "model/finalize.hpp"
#include "model/workspace.hpp"

namespace phymul {

namespace detail {

template <class T>
Owned<T>::Owned() : p_(std::make_unique<T>()) {}
template <class T>
Owned<T>::~Owned() = default;
template <class T>
Owned<T>::Owned(const Owned& other) : p_(std::make_unique<T>(*other.p_)) {}
template <class T>
Owned<T>::Owned(Owned&& other) noexcept = default;
template <class T>
Owned<T>& Owned<T>::operator=(const Owned& other) {
  if (this != &other) *p_ = *other.p_;
  return *this;
}
template <class T>
Owned<T>& Owned<T>::operator=(Owned&& other) noexcept = default;

template class Owned<Workspace>;

}  // namespace detail

namespace {

void init_bodies(const Model& model, Data& d) {
  d.bodies.assign(model.rigid_bodies.size(), RigidBodyState{});
  for (size_t b = 0; b < model.rigid_bodies.size(); ++b) {
    d.bodies[b].center = model.rigid_bodies[b].rest_center;
    d.bodies[b].orientation = model.rigid_bodies[b].rest_orientation;
  }
}

// The model's schedules, as the controls start.
void init_controls(const Model& model, Controls& c) {
  for (const RigidObstacle& o : model.obstacles) c.obstacle_motion.push_back(o.motion);
  for (const PressureLoad& p : model.pressures) c.pressure.push_back(p.pressure);
  for (const VolumeConstraint& v : model.volumes) c.target_volume.push_back(v.target_schedule);
  for (const RigidBody& b : model.rigid_bodies) {
    c.body_translation.push_back(b.translation);
    c.body_rotation.push_back(b.rotation);
  }
  for (const Needle& n : model.needles) c.needle_depth.push_back(n.depth);
}

// Each needle untouched, its track and events reserved at their most: a step allocates
// nothing.
void init_needles(const Model& model, Data& d) {
  d.needles.resize(model.needles.size());
  for (size_t k = 0; k < model.needles.size(); ++k) {
    NeedleState& s = d.needles[k];
    s.phase.assign(model.needles[k].tissues.size(), needle_outside);
    s.track.reserve(size_t(model.needles[k].track_capacity));
    s.punctures.reserve(kMaxPunctures);
    s.depth = s.last_point_depth = model.needles[k].depth.at(0.0).x();
  }
}

// Every buffer a step uses, at its size: a step allocates nothing.
void allocate_workspace(const Model& model, Workspace& w) {
  const size_t n = model.rest_position.size();
  w.x_start.assign(n, Vec3::Zero());
  w.v_start.assign(n, Vec3::Zero());
  w.f_start.assign(n, Vec3::Zero());
  if (model.settings.integrator == Integrator::newton_cotes) {  // only it needs them
    w.a1.assign(n, Vec3::Zero());
    w.scratch.assign(n, Vec3::Zero());
  }
  if (!model.obstacles.empty()) w.contacts.reserve(n * model.obstacles.size());
  w.contact_impulse.assign(model.obstacles.size(), Vec3::Zero());
  w.pair_impulse.assign(model.contact_pairs.size(), Vec3::Zero());
  w.pair_hashes.resize(model.contact_pairs.size());
  for (size_t k = 0; k < model.contact_pairs.size(); ++k)
    for (int side = 0; side < 2; ++side)
      w.pair_hashes[k][size_t(side)].reserve(model.contact_pairs[k].faces[size_t(side)].size());
  if (!model.contact_pairs.empty()) w.vertex_normal.assign(n, Vec3::Zero());
  w.pair_pushed.assign(pair_contact_capacity(model), 0.0);
  const Vec3 none = Vec3::Constant(std::numeric_limits<double>::quiet_NaN());
  w.volumes.resize(model.volumes.size());
  for (size_t k = 0; k < model.volumes.size(); ++k) {
    const size_t count = model.volumes[k].nodes.size();
    w.volumes[k].direction.assign(model.coupled_volumes ? count : 0, Vec3::Zero());
    w.volumes[k].gradient.assign(count, Vec3::Zero());
    w.volumes[k].gradient_at.assign(count, none);
  }
  w.joint.factor.assign(model.coupled_volumes ? size_t(kMaxJointVolumes * kMaxJointVolumes) : 0,
                        0.0);
  w.joint.factor_valid = false;
  w.joint.scatter.assign(model.coupled_volumes ? coupled_scatter_size(n) : 0, 0.0);
  for (const ShapeMemory& m : model.shape_memory)
    w.shape_memory_blocks.emplace_back(size_t(m.plan.blocks()), 0.0);
  for (const ExplicitFem& e : model.explicit_fem)
    w.fem_blocks.emplace_back(size_t(e.plan.blocks()), 0.0);
}

// The Anderson ring's place and fill within its columns (kAndersonDepth where it is kept).
void check_ring(const AndersonHistory& made, const AndersonHistory& got, const std::string& path,
                std::string& mismatch) {
  if (!mismatch.empty()) return;
  const int depth = made.gram.empty() ? 0 : kAndersonDepth;
  if (got.count < 0 || got.count > depth)
    mismatch = fmt::format("'{}.count' is {}, expected 0 to {}", path, got.count, depth);
  else if (got.newest < -1 || got.newest >= depth || (got.count > 0) != (got.newest >= 0))
    mismatch = fmt::format("'{}.newest' is {}, expected {}", path, got.newest,
                           got.count > 0 ? fmt::format("0 to {}", depth - 1) : "-1");
}

// Every array of `got` against the same one of `made` (allocate_data's), nested ones
// included.
template <class T>
void compare_shape(const T& made, const T& got, const std::string& path, std::string& mismatch) {
  if (!mismatch.empty()) return;
  if constexpr (fields::is_vector<T>) {
    // An array allocate_data leaves empty with room reserved is a list of at most that many.
    const bool list = made.empty() && made.capacity() > 0;
    if (list ? got.size() > made.capacity() : got.size() != made.size()) {
      mismatch = fmt::format("'{}' has {} entries where the model {} {}", path, got.size(),
                             list ? "allows at most" : "has", list ? made.capacity() : made.size());
      return;
    }
    if constexpr (fields::is_vector<typename T::value_type> ||
                  std::is_same_v<typename T::value_type, Schedule> ||
                  std::is_same_v<typename T::value_type, NeedleState>)
      for (size_t k = 0; k < made.size(); ++k)
        compare_shape(made[k], got[k], fmt::format("{}[{}]", path, k), mismatch);
  } else if constexpr (std::is_same_v<T, Schedule>) {
    if (got.times.size() != got.values.size())
      mismatch =
          fmt::format("'{}' has {} times and {} values", path, got.times.size(), got.values.size());
  } else if constexpr (std::is_same_v<T, NeedleState> || std::is_same_v<T, AndersonHistory>) {
    fields::for_each_pair(made, got, [&](std::string_view name, const auto& a, const auto& b) {
      using M = std::remove_cvref_t<decltype(a)>;
      if constexpr (fields::is_vector<M>)
        compare_shape(a, b, path + "." + std::string(name), mismatch);
    });
    if constexpr (std::is_same_v<T, AndersonHistory>) check_ring(made, got, path, mismatch);
  } else if constexpr (std::is_same_v<T, Controls>) {
    fields::for_each_pair(made, got, [&](std::string_view name, const auto& a, const auto& b) {
      if (name == "applied_force") return;  // checked with Data's node count below
      compare_shape(a, b, path + "." + std::string(name), mismatch);
    });
  } else if constexpr (std::is_same_v<T, Data>) {
    fields::for_each_pair(made, got, [&](std::string_view name, const auto& a, const auto& b) {
      compare_shape(a, b, path + "." + std::string(name), mismatch);
    });
    // Applied forces: none, or one per node.
    const size_t forces = got.controls.applied_force.size();
    if (mismatch.empty() && forces != 0 && forces != got.x.size())
      mismatch = fmt::format(
          "'{}.controls.applied_force' has {} entries where the model has {} "
          "nodes (or none)",
          path, forces, got.x.size());
  }
}

template <class T>
void assign_member(T& to, const T& from) {
  if constexpr (fields::is_workspace<T>)
    return;
  else if constexpr (fields::is_vector<T>)
    to.assign(from.begin(), from.end());  // keeps to's storage when it is large enough
  else
    to = from;
}

}  // namespace

size_t pair_contact_capacity(const Model& model) {
  size_t nodes = 0;
  for (const ContactPair& pair : model.contact_pairs)
    nodes += pair.nodes[0].size() + pair.nodes[1].size();
  return nodes * size_t(kPairContactSweeps);
}

bool anderson_applies(const Model& model) {
  return model.settings.integrator == Integrator::implicit && model.contact_pairs.empty() &&
         model.rigid_bodies.empty();
}

Data allocate_data(const Model& model) {
  Data d;
  const size_t n = model.rest_position.size();
  d.x = model.rest_position;
  d.v.assign(n, Vec3::Zero());
  d.f.assign(n, Vec3::Zero());
  if (model.settings.integrator == Integrator::implicit) d.acceleration.assign(n, Vec3::Zero());
  if (anderson_applies(model)) {
    d.anderson.df.assign(size_t(kAndersonDepth) * n, Vec3::Zero());
    d.anderson.dg.assign(size_t(kAndersonDepth) * n, Vec3::Zero());
    d.anderson.gram.assign(size_t(kAndersonDepth * kAndersonDepth), 0.0);
  }
  size_t memory_nodes = 0;
  for (const ShapeMemory& m : model.shape_memory) memory_nodes += m.nodes.size();
  d.rotation.assign(memory_nodes, Eigen::Quaterniond::Identity());
  if (model.settings.integrator == Integrator::implicit ||
      (model.settings.mode == SolveMode::static_equilibrium &&
       model.settings.solver == StaticSolver::implicit)) {
    size_t cells = 0;
    for (const ExplicitFem& fem : model.explicit_fem) cells += fem.volume.size();
    d.cell_rotation.assign(cells, Eigen::Quaterniond::Identity());
  }
  init_bodies(model, d);
  d.contact_force.assign(model.obstacles.size(), Vec3::Zero());
  d.pair_contact_force.assign(model.contact_pairs.size(), Vec3::Zero());
  if (!model.obstacles.empty()) d.obstacle_touching.assign(n, -1);
  d.pair_contacts.reserve(pair_contact_capacity(model));
  init_needles(model, d);
  init_controls(model, d.controls);
  allocate_workspace(model, *d.work);
  return d;
}

std::string data_shape_mismatch(const Model& model, const Data& data) {
  std::string mismatch;
  compare_shape(allocate_data(model), data, "data", mismatch);
  return mismatch;
}

void assign_data(Data& to, const Data& from) {
  fields::for_each_pair(to, from,
                        [](std::string_view, auto& a, const auto& b) { assign_member(a, b); });
}

}  // namespace phymul
