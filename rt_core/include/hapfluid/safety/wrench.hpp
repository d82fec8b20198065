// The small value types of the 1 kHz path: a 3-vector, a quaternion and a wrench, with the few
// operations the safety layer and the wrench renderers need. Header-only, no allocation.
#pragma once

#include <cmath>

namespace hapfluid::safety {

struct V3 {
  double x = 0, y = 0, z = 0;
  double& operator[](int i) { return i == 0 ? x : i == 1 ? y : z; }
  double operator[](int i) const { return i == 0 ? x : i == 1 ? y : z; }
  friend V3 operator+(V3 a, V3 b) { return {a.x + b.x, a.y + b.y, a.z + b.z}; }
  friend V3 operator-(V3 a, V3 b) { return {a.x - b.x, a.y - b.y, a.z - b.z}; }
  friend V3 operator*(double s, V3 a) { return {s * a.x, s * a.y, s * a.z}; }
  friend bool operator==(const V3&, const V3&) = default;
};
inline double dot(V3 a, V3 b) { return a.x * b.x + a.y * b.y + a.z * b.z; }
inline double norm(V3 a) { return std::sqrt(dot(a, a)); }
inline V3 cross(V3 a, V3 b) { return {a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x}; }
inline bool finite(V3 a) { return std::isfinite(a.x) && std::isfinite(a.y) && std::isfinite(a.z); }
inline V3 from(const double* p) { return {p[0], p[1], p[2]}; }
inline void to(V3 a, double* p) { p[0] = a.x, p[1] = a.y, p[2] = a.z; }

// Unit quaternion (w, x, y, z).
struct Quat {
  double w = 1, x = 0, y = 0, z = 0;
};
inline Quat quat_from(const double* p) { return {p[0], p[1], p[2], p[3]}; }
inline void to(Quat q, double* p) { p[0] = q.w, p[1] = q.x, p[2] = q.y, p[3] = q.z; }
inline Quat conjugate(Quat q) { return {q.w, -q.x, -q.y, -q.z}; }
inline Quat operator*(Quat a, Quat b) {
  return {a.w * b.w - a.x * b.x - a.y * b.y - a.z * b.z, a.w * b.x + a.x * b.w + a.y * b.z - a.z * b.y,
          a.w * b.y - a.x * b.z + a.y * b.w + a.z * b.x, a.w * b.z + a.x * b.y - a.y * b.x + a.z * b.w};
}
inline Quat normalized(Quat q) {
  double n = std::sqrt(q.w * q.w + q.x * q.x + q.y * q.y + q.z * q.z);
  if (!(n > 1e-12) || !std::isfinite(n)) return {};
  return {q.w / n, q.x / n, q.y / n, q.z / n};
}
inline V3 rotate(Quat q, V3 v) {
  V3 u{q.x, q.y, q.z};
  V3 t = 2.0 * cross(u, v);
  return v + q.w * t + cross(u, t);
}
// Rotation vector (axis * angle, rad) of q, taking the shorter way round.
inline V3 rotation_vector(Quat q) {
  q = normalized(q);
  if (q.w < 0) q = {-q.w, -q.x, -q.y, -q.z};
  V3 axis{q.x, q.y, q.z};
  double s = norm(axis);
  if (s < 1e-12) return 2.0 * axis;  // small-angle limit
  double angle = 2.0 * std::atan2(s, q.w);
  return (angle / s) * axis;
}

// The unit quaternion of a rotation vector (axis * angle, rad): the inverse of rotation_vector.
inline Quat quat_from_rotation_vector(V3 r) {
  double angle = norm(r);
  if (angle < 1e-12) return normalized({1.0, 0.5 * r.x, 0.5 * r.y, 0.5 * r.z});
  double s = std::sin(0.5 * angle) / angle;
  return {std::cos(0.5 * angle), s * r.x, s * r.y, s * r.z};
}

struct Wrench {
  V3 force_n;
  V3 torque_nm;
  friend bool operator==(const Wrench&, const Wrench&) = default;
};
inline Wrench operator+(Wrench a, Wrench b) { return {a.force_n + b.force_n, a.torque_nm + b.torque_nm}; }
inline Wrench operator-(Wrench a, Wrench b) { return {a.force_n - b.force_n, a.torque_nm - b.torque_nm}; }
inline Wrench operator*(double s, Wrench a) { return {s * a.force_n, s * a.torque_nm}; }
inline bool finite(const Wrench& w) { return finite(w.force_n) && finite(w.torque_nm); }

}  // namespace hapfluid::safety
