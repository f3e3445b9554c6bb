// Frictionless contact between two deformable components (not stitched): every surface node
// of one is kept out of the other's closed boundary, node against triangle, found through a
// spatial hash (DESIGN 2.3 step 4, after rigid obstacles and before volumes).
#pragma once

#include <array>
#include <span>
#include <vector>

#include "model/workspace.hpp"
#include "phymul/model.hpp"

namespace phymul {

// Closest point of triangle (a, b, c) to p, as barycentric weights (sum 1, each >= 0).
Vec3 closest_barycentric(const Vec3& p, const Vec3& a, const Vec3& b, const Vec3& c);

// Area-weighted vertex normals of a closed surface (normal, at its nodes): a smooth outward
// field whose sign test is right at edges and corners too, where a single face normal is not.
void vertex_normals(const std::vector<Triangle>& faces, const std::vector<int>& nodes,
                    std::span<const Vec3> x, std::vector<Vec3>& normal);

// The point of pair side `other`'s surface closest to p, within margin (face -1: none), with
// p's signed distance to it (m, negative inside: the sign along the interpolated vertex
// normals, filled by vertex_normals) and the way out: unit, the distance's gradient ((q - p)/d
// inside, (p - q)/d outside), the face's normal for p on the face.
struct SurfacePoint {
  double depth = 0.0;
  int face = -1;
  Vec3 weights = Vec3::Zero(), normal = Vec3::Zero();
};
SurfacePoint nearest_surface_point(const ContactPair& pair, int other, TriangleHash& hash,
                                   const std::vector<Vec3>& vertex_normal, std::span<const Vec3> x,
                                   const Vec3& p, double margin);

// Side `other` of a pair at x made ready for nearest_surface_point (its hash and vertex
// normals), and the box within its margin: only nodes in it can touch it, and most are not.
struct SurfaceReach {
  Vec3 lo, hi;
  bool contains(const Vec3& p) const {
    return (p.array() >= lo.array()).all() && (p.array() <= hi.array()).all();
  }
};
SurfaceReach prepare_surface(const ContactPair& pair, int other, std::span<const Vec3> x,
                             TriangleHash& hash, std::vector<Vec3>& vertex_normal);

// Position stage: Gauss-Seidel sweeps over the surface nodes of every pair; a node inside the
// other surface (signed distance along the interpolated vertex normal below zero) and its
// closest triangle move apart along that normal, in proportion to their inverse masses, until
// it lies on the surface, recorded in `contacts` (cleared first; capacity
// pair_contact_capacity). pair_impulse[k] gains the momentum (N s) given to the first
// component of pair k.
void apply_deformable_contacts(const Model& model, std::span<Vec3> x, Workspace& work,
                               std::vector<PairContact>& contacts, double dt,
                               std::span<Vec3> pair_impulse);

// Velocity stage: removes the approaching normal velocity of each recorded node relative to
// its triangle, momentum-conserving, by projected Gauss-Seidel sweeps (each record's impulse
// kept >= 0: pushed, pair_contacts long, holds them); adds the first components' m dv to
// pair_impulse. Returns the largest relative speed a sweep changed (m/s).
double apply_deformable_contact_velocities(const Model& model, std::span<Vec3> v,
                                           std::span<PairContact> contacts,
                                           std::span<Vec3> pair_impulse, std::span<double> pushed);

// Adds to r (N, per node) the contact forces of the last step (impulse / dt on each recorded
// node, minus it spread on its triangle): what a static residual takes out, as the contact
// balances it.
void add_deformable_contact_forces(std::span<const PairContact> contacts, double dt,
                                   std::span<Vec3> r);

}  // namespace phymul
