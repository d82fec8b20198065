// Small double-precision vector, matrix and quaternion helpers for rigid-body state. Particles
// are float (as on the GPU); bodies, couplings and mass properties are double.
#pragma once

#include <cmath>

#include "hapfluid/config/types.hpp"

namespace hapfluid::sim {

struct Vec3 {
  double x = 0, y = 0, z = 0;
  Vec3& operator+=(const Vec3& o) { x += o.x; y += o.y; z += o.z; return *this; }
  Vec3& operator-=(const Vec3& o) { x -= o.x; y -= o.y; z -= o.z; return *this; }
  Vec3& operator*=(double s) { x *= s; y *= s; z *= s; return *this; }
  double operator[](int i) const { return i == 0 ? x : i == 1 ? y : z; }
};
inline Vec3 operator+(Vec3 a, const Vec3& b) { return a += b; }
inline Vec3 operator-(Vec3 a, const Vec3& b) { return a -= b; }
inline Vec3 operator-(const Vec3& a) { return {-a.x, -a.y, -a.z}; }
inline Vec3 operator*(Vec3 a, double s) { return a *= s; }
inline Vec3 operator*(double s, Vec3 a) { return a *= s; }
inline double dot(const Vec3& a, const Vec3& b) { return a.x * b.x + a.y * b.y + a.z * b.z; }
inline Vec3 cross(const Vec3& a, const Vec3& b) {
  return {a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x};
}
inline double norm(const Vec3& a) { return std::sqrt(dot(a, a)); }
inline bool finite(const Vec3& a) { return std::isfinite(a.x) && std::isfinite(a.y) && std::isfinite(a.z); }

inline Vec3 from_config(const config::Vec3& v) { return {v.x, v.y, v.z}; }

// Row-major 3x3 matrix.
struct Mat3 {
  double m[3][3] = {{0, 0, 0}, {0, 0, 0}, {0, 0, 0}};
  static Mat3 identity() {
    Mat3 r;
    r.m[0][0] = r.m[1][1] = r.m[2][2] = 1;
    return r;
  }
};
inline Vec3 operator*(const Mat3& a, const Vec3& v) {
  return {a.m[0][0] * v.x + a.m[0][1] * v.y + a.m[0][2] * v.z, a.m[1][0] * v.x + a.m[1][1] * v.y + a.m[1][2] * v.z,
          a.m[2][0] * v.x + a.m[2][1] * v.y + a.m[2][2] * v.z};
}
inline Mat3 operator*(const Mat3& a, const Mat3& b) {
  Mat3 r;
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) r.m[i][j] = a.m[i][0] * b.m[0][j] + a.m[i][1] * b.m[1][j] + a.m[i][2] * b.m[2][j];
  return r;
}
inline Mat3 transpose(const Mat3& a) {
  Mat3 r;
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) r.m[i][j] = a.m[j][i];
  return r;
}
inline Mat3 inverse(const Mat3& a) {
  const auto& m = a.m;
  const double det = m[0][0] * (m[1][1] * m[2][2] - m[1][2] * m[2][1]) - m[0][1] * (m[1][0] * m[2][2] - m[1][2] * m[2][0]) +
                     m[0][2] * (m[1][0] * m[2][1] - m[1][1] * m[2][0]);
  Mat3 r;
  const double s = 1.0 / det;
  r.m[0][0] = (m[1][1] * m[2][2] - m[1][2] * m[2][1]) * s;
  r.m[0][1] = (m[0][2] * m[2][1] - m[0][1] * m[2][2]) * s;
  r.m[0][2] = (m[0][1] * m[1][2] - m[0][2] * m[1][1]) * s;
  r.m[1][0] = (m[1][2] * m[2][0] - m[1][0] * m[2][2]) * s;
  r.m[1][1] = (m[0][0] * m[2][2] - m[0][2] * m[2][0]) * s;
  r.m[1][2] = (m[0][2] * m[1][0] - m[0][0] * m[1][2]) * s;
  r.m[2][0] = (m[1][0] * m[2][1] - m[1][1] * m[2][0]) * s;
  r.m[2][1] = (m[0][1] * m[2][0] - m[0][0] * m[2][1]) * s;
  r.m[2][2] = (m[0][0] * m[1][1] - m[0][1] * m[1][0]) * s;
  return r;
}

struct Quat {
  double w = 1, x = 0, y = 0, z = 0;
};
inline Quat operator*(const Quat& a, const Quat& b) {
  return {a.w * b.w - a.x * b.x - a.y * b.y - a.z * b.z, a.w * b.x + a.x * b.w + a.y * b.z - a.z * b.y,
          a.w * b.y - a.x * b.z + a.y * b.w + a.z * b.x, a.w * b.z + a.x * b.y - a.y * b.x + a.z * b.w};
}
inline Quat conjugate(const Quat& q) { return {q.w, -q.x, -q.y, -q.z}; }
inline Quat normalized(const Quat& q) {
  const double n = std::sqrt(q.w * q.w + q.x * q.x + q.y * q.y + q.z * q.z);
  return {q.w / n, q.x / n, q.y / n, q.z / n};
}
inline Quat from_config(const config::Quat& q) { return normalized({q.w, q.x, q.y, q.z}); }
inline Mat3 rotation_matrix(const Quat& q) {
  Mat3 r;
  r.m[0][0] = 1 - 2 * (q.y * q.y + q.z * q.z);
  r.m[0][1] = 2 * (q.x * q.y - q.w * q.z);
  r.m[0][2] = 2 * (q.x * q.z + q.w * q.y);
  r.m[1][0] = 2 * (q.x * q.y + q.w * q.z);
  r.m[1][1] = 1 - 2 * (q.x * q.x + q.z * q.z);
  r.m[1][2] = 2 * (q.y * q.z - q.w * q.x);
  r.m[2][0] = 2 * (q.x * q.z - q.w * q.y);
  r.m[2][1] = 2 * (q.y * q.z + q.w * q.x);
  r.m[2][2] = 1 - 2 * (q.x * q.x + q.y * q.y);
  return r;
}
inline Vec3 rotate(const Quat& q, const Vec3& v) { return rotation_matrix(q) * v; }
// Rotation by the vector w * dt (axis w/|w|, angle |w| dt): the exact update of an orientation
// under a constant angular velocity over one step.
inline Quat rotation_from_vector(const Vec3& rotation_vector) {
  const double angle = norm(rotation_vector);
  if (angle < 1e-15) return {1, 0.5 * rotation_vector.x, 0.5 * rotation_vector.y, 0.5 * rotation_vector.z};
  const double s = std::sin(angle / 2) / angle;
  return {std::cos(angle / 2), rotation_vector.x * s, rotation_vector.y * s, rotation_vector.z * s};
}
// The rotation vector (axis * angle, angle in [0, pi]) of a unit quaternion: the shortest way.
inline Vec3 rotation_vector(Quat q) {
  if (q.w < 0) q = {-q.w, -q.x, -q.y, -q.z};
  const double s = std::sqrt(q.x * q.x + q.y * q.y + q.z * q.z);
  if (s < 1e-15) return {2 * q.x, 2 * q.y, 2 * q.z};
  const double angle = 2 * std::atan2(s, q.w);
  return Vec3{q.x, q.y, q.z} * (angle / s);
}

}  // namespace hapfluid::sim
