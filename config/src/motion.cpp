#include "hapfluid/config/motion.hpp"

#include <algorithm>
#include <cmath>

namespace hapfluid::config {
namespace {

constexpr double kPi = 3.14159265358979323846;

Vec3 add(Vec3 a, Vec3 b) { return {a.x + b.x, a.y + b.y, a.z + b.z}; }
Vec3 sub(Vec3 a, Vec3 b) { return {a.x - b.x, a.y - b.y, a.z - b.z}; }
Vec3 mul(Vec3 a, double s) { return {a.x * s, a.y * s, a.z * s}; }

Quat qmul(Quat a, Quat b) {
  return {a.w * b.w - a.x * b.x - a.y * b.y - a.z * b.z, a.w * b.x + a.x * b.w + a.y * b.z - a.z * b.y,
          a.w * b.y - a.x * b.z + a.y * b.w + a.z * b.x, a.w * b.z + a.x * b.y - a.y * b.x + a.z * b.w};
}
Quat conj(Quat q) { return {q.w, -q.x, -q.y, -q.z}; }
Quat axis_angle(Vec3 axis, double angle) {
  double s = std::sin(angle / 2);
  return {std::cos(angle / 2), axis.x * s, axis.y * s, axis.z * s};
}
Vec3 rotate(Quat q, Vec3 v) {
  Quat r = qmul(qmul(q, Quat{0, v.x, v.y, v.z}), conj(q));
  return {r.x, r.y, r.z};
}
Quat normalized(Quat q) {
  double n = std::sqrt(q.w * q.w + q.x * q.x + q.y * q.y + q.z * q.z);
  return {q.w / n, q.x / n, q.y / n, q.z / n};
}

Quat slerp(Quat a, Quat b, double u) {
  double dot = a.w * b.w + a.x * b.x + a.y * b.y + a.z * b.z;
  if (dot < 0) {  // shortest path
    b = {-b.w, -b.x, -b.y, -b.z};
    dot = -dot;
  }
  if (dot > 0.9995) {
    return normalized({a.w + u * (b.w - a.w), a.x + u * (b.x - a.x), a.y + u * (b.y - a.y), a.z + u * (b.z - a.z)});
  }
  double theta = std::acos(dot);
  double sa = std::sin((1 - u) * theta) / std::sin(theta), sb = std::sin(u * theta) / std::sin(theta);
  return {sa * a.w + sb * b.w, sa * a.x + sb * b.x, sa * a.y + sb * b.y, sa * a.z + sb * b.z};
}

// Angle swept by a spin whose speed ramps linearly up over ramp_s, holds, and ramps down.
double spin_angle(const MotionSegment& s, double tau) {
  const double duration = s.stop_s - s.start_s, ramp = s.ramp_s, w = s.angular_speed_rad_s;
  tau = std::clamp(tau, 0.0, duration);
  if (ramp <= 0) return w * tau;
  if (tau < ramp) return 0.5 * w * tau * tau / ramp;
  const double up = 0.5 * w * ramp;
  if (tau < duration - ramp) return up + w * (tau - ramp);
  const double down_tau = tau - (duration - ramp);
  return up + w * (duration - 2 * ramp) + w * down_tau - 0.5 * w * down_tau * down_tau / ramp;
}

// Amplitude envelope of an oscillation: smoothstep in over ramp_s, out over the last ramp_s.
double oscillate_envelope(const MotionSegment& s, double tau) {
  if (s.ramp_s <= 0) return 1.0;
  const double duration = s.stop_s - s.start_s;
  const double u = std::clamp(std::min(tau, duration - tau) / s.ramp_s, 0.0, 1.0);
  return u * u * (3 - 2 * u);
}

// Tilt to angle_rad along a half-cosine, hold, and return the same way: smooth, so a scripted
// hand never asks the device for a velocity step.
double tilt_angle(const MotionSegment& s, double tau) {
  const double duration = s.stop_s - s.start_s;
  tau = std::clamp(tau, 0.0, duration);
  const double rise = (duration - s.hold_s) / 2;
  if (tau < rise) return s.angle_rad * 0.5 * (1 - std::cos(kPi * tau / rise));
  if (tau < rise + s.hold_s) return s.angle_rad;
  const double back = tau - rise - s.hold_s;
  return s.angle_rad * 0.5 * (1 + std::cos(kPi * back / rise));
}

Pose keyframe_pose(const MotionSegment& s, double tau) {
  const auto& k = s.keyframes;
  if (k.empty()) return {};
  if (tau <= k.front().t_s) return k.front().pose;
  if (tau >= k.back().t_s) return k.back().pose;
  size_t i = 1;
  while (k[i].t_s < tau) ++i;
  const double u = (tau - k[i - 1].t_s) / (k[i].t_s - k[i - 1].t_s);
  const Pose &a = k[i - 1].pose, &b = k[i].pose;
  return {add(a.position_m, mul(sub(b.position_m, a.position_m), u)), slerp(a.orientation, b.orientation, u)};
}

void rotate_about(Pose& pose, Vec3 pivot, Quat rotation) {
  pose.position_m = add(pivot, rotate(rotation, sub(pose.position_m, pivot)));
  pose.orientation = normalized(qmul(rotation, pose.orientation));
}

Pose evaluate_pose(const ScriptedMotion& motion, double t) {
  Pose pose = motion.start;
  for (const auto& s : motion.segments) {
    const double tau = std::clamp(t, s.start_s, s.stop_s) - s.start_s;
    const Vec3 pivot = add(motion.start.position_m, s.pivot_offset_m);
    switch (s.kind) {
      case MotionKind::oscillate:
        pose.position_m = add(pose.position_m, mul(s.axis, s.amplitude_m * oscillate_envelope(s, tau) *
                                                                   std::sin(2 * kPi * s.frequency_hz * tau)));
        break;
      case MotionKind::spin: rotate_about(pose, pivot, axis_angle(s.axis, spin_angle(s, tau))); break;
      case MotionKind::tilt: rotate_about(pose, pivot, axis_angle(s.axis, tilt_angle(s, tau))); break;
      case MotionKind::keyframes:
        if (t >= s.start_s) pose = keyframe_pose(s, tau);
        break;
    }
  }
  return pose;
}

}  // namespace

PoseTwist evaluate_motion(const ScriptedMotion& motion, double t_s) {
  constexpr double h = 1e-6;
  PoseTwist out;
  out.pose = evaluate_pose(motion, t_s);
  const Pose before = evaluate_pose(motion, t_s - h), after = evaluate_pose(motion, t_s + h);
  out.linear_velocity_m_s = mul(sub(after.position_m, before.position_m), 1 / (2 * h));
  // World angular velocity from dq: q_after = exp(w * 2h / 2) q_before.
  Quat dq = qmul(after.orientation, conj(before.orientation));
  if (dq.w < 0) dq = {-dq.w, -dq.x, -dq.y, -dq.z};
  out.angular_velocity_rad_s = mul(Vec3{dq.x, dq.y, dq.z}, 2 / (2 * h));
  return out;
}

const char* to_string(MotionKind k) {
  switch (k) {
    case MotionKind::keyframes: return "keyframes";
    case MotionKind::oscillate: return "oscillate";
    case MotionKind::spin: return "spin";
    case MotionKind::tilt: return "tilt";
  }
  return "?";
}

}  // namespace hapfluid::config
