// Scripted hands: the paper's motions (stir, spin, tilt, keyframes) as pure functions of time.
// A hand that jumps would ask a device for an impossible velocity step, so continuity matters.
#include <gtest/gtest.h>

#include <cmath>

#include "hapfluid/config/motion.hpp"

using namespace hapfluid::config;

namespace {
constexpr double kPi = 3.14159265358979323846;

double quat_angle_about_z(const Quat& q) { return 2 * std::atan2(q.z, q.w); }
double norm(const Quat& q) { return std::sqrt(q.w * q.w + q.x * q.x + q.y * q.y + q.z * q.z); }
}  // namespace

TEST(Motion, NoSegmentsHoldsTheStartPose) {
  ScriptedMotion m{{{0.1, 0.2, 0.3}, {1, 0, 0, 0}}, {}};
  PoseTwist p = evaluate_motion(m, 5.0);
  EXPECT_DOUBLE_EQ(p.pose.position_m.x, 0.1);
  EXPECT_NEAR(p.linear_velocity_m_s.x, 0.0, 1e-9);
}

TEST(Motion, OscillateIsASineWithItsExactDerivative) {
  MotionSegment s;
  s.kind = MotionKind::oscillate;
  s.axis = {1, 0, 0};
  s.amplitude_m = 0.08;
  s.frequency_hz = 0.5;
  s.start_s = 1.0;
  s.stop_s = 7.0;
  ScriptedMotion m{{{0.2, 0.15, 0.3}, {}}, {s}};
  for (double t : {1.1, 1.3, 2.0, 4.7, 6.9}) {
    PoseTwist p = evaluate_motion(m, t);
    const double phase = 2 * kPi * 0.5 * (t - 1.0);
    EXPECT_NEAR(p.pose.position_m.x, 0.2 + 0.08 * std::sin(phase), 1e-12);
    EXPECT_NEAR(p.linear_velocity_m_s.x, 0.08 * 2 * kPi * 0.5 * std::cos(phase), 1e-5);
  }
  // Three full strokes end where they began: the hand is back at rest position after stop_s.
  EXPECT_NEAR(evaluate_motion(m, 9.0).pose.position_m.x, 0.2, 1e-12);
  EXPECT_NEAR(evaluate_motion(m, 9.0).linear_velocity_m_s.x, 0.0, 1e-9);
}

TEST(Motion, OscillateWithARampStartsAndStopsWithoutAVelocityStep) {
  MotionSegment s;
  s.kind = MotionKind::oscillate;
  s.axis = {0, 1, 0};
  s.amplitude_m = 0.08;
  s.frequency_hz = 0.5;
  s.ramp_s = 0.5;
  s.start_s = 1.0;
  s.stop_s = 7.0;
  ScriptedMotion m{{{0, 0, 0}, {}}, {s}};
  for (double t : {0.9, 1.0, 1.0001, 6.9999, 7.0})
    EXPECT_NEAR(evaluate_motion(m, t).linear_velocity_m_s.y, 0.0, 2e-3) << "t = " << t;
  // Past the ramp the full amplitude is reached.
  EXPECT_NEAR(evaluate_motion(m, 3.5).pose.position_m.y, 0.08, 1e-12);
}

TEST(Motion, SpinRampsUpHoldsSpeedAndStopsWithoutJumps) {
  MotionSegment s;
  s.kind = MotionKind::spin;
  s.axis = {0, 0, 1};
  s.angular_speed_rad_s = 2 * kPi;
  s.ramp_s = 0.2;
  s.start_s = 1.0;
  s.stop_s = 4.0;
  ScriptedMotion m{{{0.15, 0.15, 0.1}, {}}, {s}};
  EXPECT_NEAR(evaluate_motion(m, 0.5).angular_velocity_rad_s.z, 0.0, 1e-9);      // rest
  EXPECT_NEAR(evaluate_motion(m, 1.1).angular_velocity_rad_s.z, kPi, 1e-4);      // half-way up the ramp
  EXPECT_NEAR(evaluate_motion(m, 2.5).angular_velocity_rad_s.z, 2 * kPi, 1e-4);  // spinning
  EXPECT_NEAR(evaluate_motion(m, 4.5).angular_velocity_rad_s.z, 0.0, 1e-9);      // stopped
  // Total angle: speed x (duration - ramp). Compare modulo a turn via the quaternion.
  const double total = 2 * kPi * (3.0 - 0.2);
  const double got = quat_angle_about_z(evaluate_motion(m, 5.0).pose.orientation);
  EXPECT_NEAR(std::remainder(got - total, 2 * kPi), 0.0, 1e-9);
  // Continuity: no step in orientation between neighbouring milliseconds anywhere.
  Quat prev = evaluate_motion(m, 0.0).pose.orientation;
  for (double t = 0.001; t < 5.0; t += 0.001) {
    Quat q = evaluate_motion(m, t).pose.orientation;
    double dot = std::abs(prev.w * q.w + prev.x * q.x + prev.y * q.y + prev.z * q.z);
    EXPECT_GT(dot, std::cos(2 * kPi * 0.001));  // at most the full speed for 1 ms
    EXPECT_NEAR(norm(q), 1.0, 1e-12);
    prev = q;
  }
}

TEST(Motion, TiltAboutAPivotReachesTheAngleAndReturns) {
  MotionSegment s;
  s.kind = MotionKind::tilt;
  s.axis = {0, 1, 0};
  s.angle_rad = kPi / 2;
  s.hold_s = 1.0;
  s.start_s = 0.0;
  s.stop_s = 3.0;
  s.pivot_offset_m = {0.1, 0, 0};
  ScriptedMotion m{{{0.0, 0.0, 0.0}, {}}, {s}};
  // At full tilt (+90 deg about y), the hand 0.1 m on -x of the pivot swings up to above it.
  PoseTwist held = evaluate_motion(m, 1.5);
  EXPECT_NEAR(held.pose.position_m.x, 0.1, 1e-12);
  EXPECT_NEAR(held.pose.position_m.z, 0.1, 1e-12);
  EXPECT_NEAR(held.angular_velocity_rad_s.y, 0.0, 1e-6);
  PoseTwist back = evaluate_motion(m, 3.0);
  EXPECT_NEAR(back.pose.position_m.x, 0.0, 1e-12);
  EXPECT_NEAR(back.pose.orientation.w, 1.0, 1e-12);
}

TEST(Motion, KeyframesInterpolatePositionAndSlerpOrientation) {
  MotionSegment s;
  s.kind = MotionKind::keyframes;
  s.start_s = 1.0;
  const double h = std::sqrt(0.5);
  s.keyframes = {{0.0, {{0, 0, 0}, {1, 0, 0, 0}}}, {2.0, {{0.2, 0, 0}, {h, 0, 0, h}}}};
  ScriptedMotion m{{{0, 0, 0}, {}}, {s}};
  PoseTwist mid = evaluate_motion(m, 2.0);
  EXPECT_NEAR(mid.pose.position_m.x, 0.1, 1e-12);
  EXPECT_NEAR(quat_angle_about_z(mid.pose.orientation), kPi / 4, 1e-9);
  EXPECT_NEAR(mid.linear_velocity_m_s.x, 0.1, 1e-6);
  EXPECT_NEAR(mid.angular_velocity_rad_s.z, kPi / 4, 1e-5);
  EXPECT_NEAR(evaluate_motion(m, 10.0).pose.position_m.x, 0.2, 1e-12);
}

TEST(Motion, SegmentsCompose) {
  MotionSegment stir;
  stir.kind = MotionKind::oscillate;
  stir.axis = {1, 0, 0};
  stir.amplitude_m = 0.05;
  stir.frequency_hz = 1.0;
  MotionSegment spin;
  spin.kind = MotionKind::spin;
  spin.axis = {0, 0, 1};
  spin.angular_speed_rad_s = 1.0;
  ScriptedMotion m{{{0, 0, 0}, {}}, {stir, spin}};
  PoseTwist p = evaluate_motion(m, 0.25);  // stir at +0.05 on x, then rotated 0.25 rad about z
  EXPECT_NEAR(p.pose.position_m.x, 0.05 * std::cos(0.25), 1e-12);
  EXPECT_NEAR(p.pose.position_m.y, 0.05 * std::sin(0.25), 1e-12);
}
