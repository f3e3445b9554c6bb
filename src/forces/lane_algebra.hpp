// The algebra of the batched shape-memory kernels: 3-vectors, 3x3 matrices and quaternions
// whose every component is a vector of lanes (GCC/Clang vector extensions), one node a lane.
// L is the lane vector (four doubles in shape_memory_batch.cpp). Constants are taken in L's
// own element type.
#pragma once

#include <type_traits>

// The helpers pass lane vectors by value; they are all inlined, so the note that AVX changes
// the calling convention of such functions does not apply.
#pragma GCC diagnostic ignored "-Wpsabi"
#define PHYMUL_LANES [[gnu::always_inline]] inline

namespace phymul::lanes {

template <class L>
using Scalar = std::remove_cvref_t<decltype(L{}[0])>;

template <class L>
struct V3 {
  L v[3];
};
template <class L>
struct M3 {
  L a[3][3];  // [row][column]
};
template <class L>
struct Q {
  L w, x, y, z;
};
// A symmetric 3x3 matrix, its upper triangle.
template <class L>
struct Sym3 {
  L m00, m01, m02, m11, m12, m22;
};

template <class L>
PHYMUL_LANES V3<L> operator+(const V3<L>& a, const V3<L>& b) {
  return {{a.v[0] + b.v[0], a.v[1] + b.v[1], a.v[2] + b.v[2]}};
}
template <class L>
PHYMUL_LANES V3<L> operator-(const V3<L>& a, const V3<L>& b) {
  return {{a.v[0] - b.v[0], a.v[1] - b.v[1], a.v[2] - b.v[2]}};
}
template <class L>
PHYMUL_LANES V3<L> operator*(const V3<L>& a, std::type_identity_t<L> s) {
  return {{a.v[0] * s, a.v[1] * s, a.v[2] * s}};
}
template <class L>
PHYMUL_LANES V3<L> operator/(const V3<L>& a, std::type_identity_t<L> s) {
  return {{a.v[0] / s, a.v[1] / s, a.v[2] / s}};
}
template <class L>
PHYMUL_LANES L dot(const V3<L>& a, const V3<L>& b) {
  return a.v[0] * b.v[0] + a.v[1] * b.v[1] + a.v[2] * b.v[2];
}
template <class L>
PHYMUL_LANES V3<L> cross(const V3<L>& a, const V3<L>& b) {
  return {{a.v[1] * b.v[2] - a.v[2] * b.v[1], a.v[2] * b.v[0] - a.v[0] * b.v[2],
           a.v[0] * b.v[1] - a.v[1] * b.v[0]}};
}

template <class L>
PHYMUL_LANES V3<L> times(const M3<L>& M, const V3<L>& u) {
  V3<L> r;
  for (int a = 0; a < 3; ++a) r.v[a] = M.a[a][0] * u.v[0] + M.a[a][1] * u.v[1] + M.a[a][2] * u.v[2];
  return r;
}
template <class L>
PHYMUL_LANES V3<L> transpose_times(const M3<L>& M, const V3<L>& u) {
  V3<L> r;
  for (int a = 0; a < 3; ++a) r.v[a] = M.a[0][a] * u.v[0] + M.a[1][a] * u.v[1] + M.a[2][a] * u.v[2];
  return r;
}
template <class L>
PHYMUL_LANES M3<L> transpose_times(const M3<L>& R, const M3<L>& A) {
  M3<L> S;
  for (int a = 0; a < 3; ++a)
    for (int b = 0; b < 3; ++b)
      S.a[a][b] = R.a[0][a] * A.a[0][b] + R.a[1][a] * A.a[1][b] + R.a[2][a] * A.a[2][b];
  return S;
}

// Eigen's Quaternion::toRotationMatrix, lane by lane.
template <class L>
PHYMUL_LANES M3<L> rotation_matrix(const Q<L>& q) {
  using S = Scalar<L>;
  const L tx = S(2) * q.x, ty = S(2) * q.y, tz = S(2) * q.z;
  const L twx = tx * q.w, twy = ty * q.w, twz = tz * q.w;
  const L txx = tx * q.x, txy = ty * q.x, txz = tz * q.x;
  const L tyy = ty * q.y, tyz = tz * q.y, tzz = tz * q.z;
  M3<L> R;
  R.a[0][0] = S(1) - (tyy + tzz), R.a[0][1] = txy - twz, R.a[0][2] = txz + twy;
  R.a[1][0] = txy + twz, R.a[1][1] = S(1) - (txx + tzz), R.a[1][2] = tyz - twx;
  R.a[2][0] = txz - twy, R.a[2][1] = tyz + twx, R.a[2][2] = S(1) - (txx + tyy);
  return R;
}

// tr(S) I - sym(S) (shape_memory.cpp's rotation_hessian).
template <class L>
PHYMUL_LANES Sym3<L> rotation_hessian(const M3<L>& M) {
  using S = Scalar<L>;
  const L trace = M.a[0][0] + M.a[1][1] + M.a[2][2];
  return {
      trace - M.a[0][0], -(S(0.5) * (M.a[0][1] + M.a[1][0])), -(S(0.5) * (M.a[0][2] + M.a[2][0])),
      trace - M.a[1][1], -(S(0.5) * (M.a[1][2] + M.a[2][1])), trace - M.a[2][2]};
}

template <class L>
PHYMUL_LANES V3<L> axial_of_skew(const M3<L>& M) {
  using S = Scalar<L>;
  return {{S(0.5) * (M.a[2][1] - M.a[1][2]), S(0.5) * (M.a[0][2] - M.a[2][0]),
           S(0.5) * (M.a[1][0] - M.a[0][1])}};
}

}  // namespace phymul::lanes
