#include "forces/shape_memory.hpp"

#include <fmt/format.h>

#include <Eigen/Eigenvalues>
#include <Eigen/SVD>
#include <algorithm>
#include <cassert>
#include <cmath>
#include <stdexcept>

#include "forces/shape_memory_batch.hpp"
#include "model/neighbourhood.hpp"
#include "model/parallel_plan.hpp"

namespace phymul {
namespace {

// tr(S) I - S for the symmetric part of S: the Hessian of -trace(R^T A) in the body frame.
Eigen::Matrix3d rotation_hessian(const Eigen::Matrix3d& S) {
  const Eigen::Matrix3d Ss = 0.5 * (S + S.transpose());
  return Ss.trace() * Eigen::Matrix3d::Identity() - Ss;
}

Vec3 axial_of_skew(const Eigen::Matrix3d& S) {
  return Vec3(0.5 * (S(2, 1) - S(1, 2)), 0.5 * (S(0, 2) - S(2, 0)), 0.5 * (S(1, 0) - S(0, 1)));
}

// Solves M y = b for a symmetric 3x3 M by its adjugate, when M is safely positive
// definite (Sylvester's criterion, and a determinant not negligible against its scale);
// an LLT or a pow() here cost a fifth of a step.
bool solve_positive_definite(const Eigen::Matrix3d& M, const Vec3& b, Vec3& y) {
  const double c00 = M(1, 1) * M(2, 2) - M(1, 2) * M(1, 2);
  const double c01 = M(0, 2) * M(1, 2) - M(0, 1) * M(2, 2);
  const double c02 = M(0, 1) * M(1, 2) - M(0, 2) * M(1, 1);
  const double det = M(0, 0) * c00 + M(0, 1) * c01 + M(0, 2) * c02;
  const double scale = M.trace() / 3.0;
  if (!(M(0, 0) > 0.0 && M(0, 0) * M(1, 1) > M(0, 1) * M(0, 1) &&
        det > 1e-6 * scale * scale * scale))
    return false;
  const double c11 = M(0, 0) * M(2, 2) - M(0, 2) * M(0, 2);
  const double c12 = M(0, 1) * M(0, 2) - M(0, 0) * M(1, 2);
  const double c22 = M(0, 0) * M(1, 1) - M(0, 1) * M(0, 1);
  y = Vec3(c00 * b(0) + c01 * b(1) + c02 * b(2), c01 * b(0) + c11 * b(1) + c12 * b(2),
           c02 * b(0) + c12 * b(1) + c22 * b(2)) *
      (1.0 / det);
  return true;
}

// q turned by the body-frame rotation vector theta (|theta|^2 = angle2). Below 1e-4 rad the
// unnormalised quaternion (1, theta/2) turns by theta to 1e-13 relative, and one Newton step
// for 1/sqrt(|q|^2) near 1 renormalises (to 1e-17, drift included): no sin, cos, sqrt or
// division on the path every node takes every step.
void turn(Eigen::Quaterniond& q, const Vec3& theta, double angle2) {
  if (angle2 < 1e-8) {
    q = q * Eigen::Quaterniond(1.0, 0.5 * theta(0), 0.5 * theta(1), 0.5 * theta(2));
    q.coeffs() *= 1.5 - 0.5 * q.squaredNorm();
    return;
  }
  const double angle = std::sqrt(angle2);
  q = q * Eigen::Quaterniond(Eigen::AngleAxisd(std::min(angle, 1.0), theta / angle));
  q.normalize();
}

struct Turn {
  double angle2 = 0.0;  // rad^2, the turn's squared angle
  bool newton = false;
};

// Turns q towards the maximiser of trace(R^T A). Near the optimum a Newton step on the
// symmetry condition skew(R^T A) = 0 (quadratic); elsewhere, or when tr(S) I - S is not
// positive definite, the step of Mueller et al. (2016) (linear, but always ascending).
Turn rotation_iteration(const Eigen::Matrix3d& A, Eigen::Quaterniond& q) {
  const Eigen::Matrix3d S = q.toRotationMatrix().transpose() * A;
  const Vec3 w = axial_of_skew(S);
  Turn result;
  Vec3 theta;  // body-frame turn
  result.newton = solve_positive_definite(rotation_hessian(S), w, theta);
  if (result.newton)
    theta *= 2.0;
  else
    theta = 2.0 * w / std::max(std::abs(S.trace()), 1e-300);
  result.angle2 = theta.squaredNorm();
  if (result.angle2 == 0.0 || !std::isfinite(result.angle2)) return {0.0, result.newton};
  turn(q, theta, result.angle2);
  return result;
}

// The proper rotation nearest to A (Kabsch): a cold start far from the warm one.
Eigen::Quaterniond nearest_rotation(const Eigen::Matrix3d& A) {
  const Eigen::JacobiSVD<Eigen::Matrix3d> svd(A, Eigen::ComputeFullU | Eigen::ComputeFullV);
  Eigen::Matrix3d U = svd.matrixU();
  if ((U * svd.matrixV().transpose()).determinant() < 0.0) U.col(2) *= -1.0;
  return Eigen::Quaterniond(U * svd.matrixV().transpose()).normalized();
}

// What the polar fit of a neighbourhood needs, computed once per node and step.
struct Fit {
  Vec3 g;                  // current centroid of the neighbours
  Vec3 G0;                 // rest centroid of the neighbours
  Eigen::Matrix3d A;       // sum (x_j - g)(X_j - G0)^T (+ the normal pair)
  Vec3 N = Vec3::Zero();   // unnormalised current normal of a flat neighbourhood
  Vec3 n0 = Vec3::Zero();  // unit rest normal of a flat neighbourhood
  Vec3 c;                  // rest offset R0^T (X_i - G0), R0 = I (ShapeMemory::rest_offset)
  double weight = 0.0;     // of the normal pair, m^2; zero: none
};

// The rest centroid and rest normal are recomputed rather than stored: 48 bytes a node less,
// for a few additions on data the pass reads anyway.
Fit fit_neighbourhood(const ShapeMemory& m, int k, std::span<const Vec3> rest,
                      std::span<const Vec3> x) {
  const auto nb = m.neighbours.row(k);
  const int i = m.nodes[k];
  // One pass, about the node itself (small differences, no cancellation):
  // sum (x_j - g)(X_j - G0)^T = sum d_j r_j^T - (sum d_j) mean(r)^T.
  // The rest positions summed plainly too: the rest offset c is not stored in polar mode
  // but recomputed, bit for bit as memorise_rest_shape computes it in frame mode (the
  // centroid's sum in the same order, the identity's product), 24 bytes a node less.
  Vec3 sum_d = Vec3::Zero(), sum_r = Vec3::Zero(), sum_X = Vec3::Zero();
  Eigen::Matrix3d P = Eigen::Matrix3d::Zero();
  for (int j : nb) {
    const Vec3 d = x[j] - x[i], r = rest[j] - rest[i];
    sum_d += d;
    sum_r += r;
    sum_X += rest[j];
    P.noalias() += d * r.transpose();
  }
  const double count = double(nb.size());
  Fit fit;
  fit.g = x[i] + sum_d / count;
  fit.G0 = rest[i] + sum_r / count;
  fit.A = P - sum_d * (sum_r / count).transpose();
  const Eigen::Matrix3d R0 = Eigen::Matrix3d::Identity();
  fit.c = R0.transpose() * (rest[i] - sum_X / count);
  fit.weight = normal_weight(m, k);
  if (fit.weight > 0.0) {
    fit.N = neighbourhood_normal(m, k, x, fit.g);
    fit.n0 = neighbourhood_normal(m, k, rest, fit.G0).normalized();
    fit.A += fit.weight * fit.N.normalized() * fit.n0.transpose();
  }
  return fit;
}

// The part of -dE/dx that flows through the best-fit rotation, E = K |a - x_i|^2 / 2 and
// a = g + R c. With A = R S (S symmetric), a change dA turns R by
// theta = 2 (tr(S) I - S)^-1 axial(skew(R^T dA)); its effect on E is carried back to every
// neighbour that enters A (and to the normal pair of flat neighbourhoods).
void add_rotation_reaction(const ShapeMemory& m, int k, std::span<const Vec3> rest,
                           std::span<const Vec3> x, const Fit& fit, const Eigen::Matrix3d& R,
                           const Vec3& pull, std::span<Vec3> f) {
  const auto nb = m.neighbours.row(k);
  const Eigen::Matrix3d M = rotation_hessian(R.transpose() * fit.A);
  const Vec3 p = m.stiffness * fit.c.cross(R.transpose() * pull);  // dE = p.theta
  Vec3 mu;
  if (!solve_positive_definite(M, p, mu)) mu = M.inverse() * p;
  mu *= 2.0;
  for (int j : nb) f[j] -= 0.5 * R * mu.cross(rest[j] - fit.G0);
  const double weight = fit.weight;
  if (weight <= 0.0) return;
  // The normal pair: dE = h'.dN, N the unnormalised neighbourhood normal.
  const Vec3 n = fit.N.normalized();
  const Vec3 h = 0.5 * weight * R * mu.cross(fit.n0);
  const Vec3 hp = (h - n.dot(h) * n) / fit.N.norm();
  const int count = int(nb.size());
  if (m.surface) {  // N = sum of e_k x e_k+1 around the ring: the centroid terms cancel
    for (int r = 0; r < count; ++r) {
      const Vec3 next = x[nb[(r + 1) % count]] - fit.g;
      const Vec3 prev = x[nb[(r + count - 1) % count]] - fit.g;
      f[nb[r]] -= (next - prev).cross(hp);
    }
    return;
  }
  const int a = nb[frame_pair(m, k)[0]], b = nb[frame_pair(m, k)[1]];
  const Vec3 ga = (x[b] - fit.g).cross(hp), gb = hp.cross(x[a] - fit.g);
  f[a] -= ga;
  f[b] -= gb;
  const Vec3 through_centroid = (ga + gb) / double(count);
  for (int j : nb) f[j] += through_centroid;
}

}  // namespace

void extract_rotation(const Eigen::Matrix3d& A, Eigen::Quaterniond& q, int max_iterations) {
  // Converged once a turn is below 1e-14 rad, or after a Newton turn below 1e-8 rad (the
  // next would be of its square): forces then sit at round-off. A warm start needs one
  // iteration; a start far away restarts from an SVD.
  auto converged = [](const Turn& t) { return t.angle2 < 1e-28 || (t.newton && t.angle2 < 1e-16); };
  for (int it = 0; it < max_iterations; ++it)
    if (converged(rotation_iteration(A, q))) return;
  q = nearest_rotation(A);
  for (int it = 0; it < max_iterations; ++it)
    if (converged(rotation_iteration(A, q))) return;
}

Vec3 attraction_position(const ShapeMemory& m, int k, std::span<const Vec3> rest,
                         std::span<const Vec3> x, Eigen::Quaterniond& q) {
  if (m.frame == FrameMode::frame) {
    const Vec3 g = centroid(m.neighbours.row(k), x);
    return g + local_frame(m, k, x, g) * m.rest_offset[k];
  }
  const Fit fit = fit_neighbourhood(m, k, rest, x);
  extract_rotation(fit.A, q);
  return fit.g + q.toRotationMatrix() * fit.c;
}

namespace {

// Spreads -f/n over the neighbours: the part of -dE/dx that flows through the centroid g.
void add_centroid_reaction(std::span<const int> nb, const Vec3& fi, std::span<Vec3> f) {
  const Vec3 share = fi / double(nb.size());
  for (int j : nb) f[j] -= share;
}

}  // namespace

double add_polar_node_forces(const ShapeMemory& m, int k, std::span<const Vec3> rest,
                             std::span<const Vec3> x, std::span<Eigen::Quaterniond> rotations,
                             std::span<Vec3> f) {
  const int i = m.nodes[k];
  const Fit fit = fit_neighbourhood(m, k, rest, x);
  extract_rotation(fit.A, rotations[k]);
  const Eigen::Matrix3d R = rotations[k].toRotationMatrix();
  const Vec3 pull = fit.g + R * fit.c - x[i];
  f[i] += m.stiffness * pull;
  if (m.reaction) {
    // -dE/dx through g and through R: the forces are then exactly the energy's gradient.
    add_centroid_reaction(m.neighbours.row(k), m.stiffness * pull, f);
    add_rotation_reaction(m, k, rest, x, fit, R, pull, f);
  }
  return 0.5 * m.stiffness * pull.squaredNorm();
}

namespace {

// Batches of kShapeMemoryLanes first, then the block's other nodes: the order is the model's,
// whatever the number of threads.
double add_polar_forces(const ShapeMemory& m, std::span<const Vec3> rest, std::span<const Vec3> x,
                        std::span<Eigen::Quaterniond> rotations, std::span<Vec3> f,
                        std::span<double> blocks) {
  // Compiling plans every polar memory's batches (plan_polar_batches), and a Model is not
  // changed after: there is no unplanned path.
  assert(polar_batches_planned(m));
  return run_coloured_blocks(m.plan, blocks, [&](int b) {
    double energy = 0.0;
    const int batched = m.batched_end[b], centred = m.centred_start[b],
              end = m.plan.block_start[b + 1];
    int p = m.plan.block_start[b];
    for (; p + 2 * kShapeMemoryLanes <= batched; p += 2 * kShapeMemoryLanes)
      add_polar_batch_pair_forces(m, m.batch_order.data() + p, rest, x, rotations, f, energy);
    for (; p < batched; p += kShapeMemoryLanes) {
      std::array<int, kShapeMemoryLanes> ks;
      std::copy_n(m.batch_order.begin() + p, kShapeMemoryLanes, ks.begin());
      energy += add_polar_batch_forces(m, ks, rest, x, rotations, f);
    }
    for (; p < centred; ++p)
      energy += add_polar_node_forces(m, m.batch_order[p], rest, x, rotations, f);
    return energy + add_centred_forces(m, m.batch_order.data() + p, end - p, x, f);
  });
}

double add_frame_forces(const ShapeMemory& m, std::span<const Vec3> rest, std::span<const Vec3> x,
                        std::span<Eigen::Quaterniond> rotations, std::span<Vec3> f,
                        std::span<double> blocks) {
  return run_coloured(m.plan, blocks, [&](int k) {
    const int i = m.nodes[k];
    const Vec3 pull = attraction_position(m, k, rest, x, rotations[k]) - x[i];
    f[i] += m.stiffness * pull;
    if (m.reaction) add_centroid_reaction(m.neighbours.row(k), m.stiffness * pull, f);
    return 0.5 * m.stiffness * pull.squaredNorm();
  });
}

}  // namespace

double add_shape_memory_forces(const ShapeMemory& m, std::span<const Vec3> rest,
                               std::span<const Vec3> x, std::span<Eigen::Quaterniond> rotations,
                               std::span<Vec3> f, std::span<double> blocks) {
  return m.frame == FrameMode::polar ? add_polar_forces(m, rest, x, rotations, f, blocks)
                                     : add_frame_forces(m, rest, x, rotations, f, blocks);
}

}  // namespace phymul
