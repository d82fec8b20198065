// Scripted hand motion: what a person's hand would do with a device in the paper's scenarios
// (§6.4: stir back and forth, pour by tilting, spin a glass, tilt a bucket), used by batch runs
// of the simulator and by the fake device. Evaluation is a pure function of time.
#pragma once

#include <string>
#include <vector>

#include "hapfluid/config/types.hpp"

namespace hapfluid::config {

struct Keyframe {
  double t_s = 0;
  Pose pose;
};

enum class MotionKind {
  keyframes,  // piecewise interpolation between poses (linear position, slerp orientation)
  oscillate,  // back-and-forth translation: amplitude * sin(2 pi f (t - start)) along an axis
  spin,       // rotation about an axis through a pivot at an angular speed, ramped in and out
  tilt,       // rotation about an axis through a pivot to an angle and back, smooth (cosine) profile
};

// One motion segment. Segments combine in order: each applies its displacement (translation and
// rotation about its pivot) to the pose produced so far, so "stir while slowly moving" is two
// segments. Outside [start_s, stop_s] a segment holds its value at the nearest end.
struct MotionSegment {
  MotionKind kind = MotionKind::oscillate;
  double start_s = 0.0;
  double stop_s = 1e9;
  // oscillate
  Vec3 axis{1, 0, 0};           // unit axis (oscillate: direction; spin/tilt: rotation axis)
  double amplitude_m = 0.0;
  double frequency_hz = 0.0;
  // spin
  double angular_speed_rad_s = 0.0;
  // spin: time to reach (and to leave) the angular speed; oscillate: time over which the
  // amplitude fades in and out (smoothstep), so the hand starts and stops without a velocity step
  double ramp_s = 0.0;
  // tilt
  double angle_rad = 0.0;
  double hold_s = 0.0;          // tilt: time spent at the full angle before returning
  Vec3 pivot_offset_m;          // spin/tilt: pivot relative to the start position (world frame)
  // keyframes (times relative to start_s; poses are absolute)
  std::vector<Keyframe> keyframes;
};

struct ScriptedMotion {
  Pose start;
  std::vector<MotionSegment> segments;
};

// Pose and twist of the scripted hand at time t (seconds since the scene started).
// Velocities are exact derivatives of the evaluated pose (central difference of 1 us).
PoseTwist evaluate_motion(const ScriptedMotion& motion, double t_s);

const char* to_string(MotionKind);

}  // namespace hapfluid::config
