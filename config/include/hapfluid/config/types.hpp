// Small value types shared by rig and scene descriptions. SI units throughout; orientations are
// unit quaternions (w, x, y, z). Kept dependency-free so every part can include it.
#pragma once

#include <array>
#include <cmath>

namespace hapfluid::config {

struct Vec3 {
  double x = 0, y = 0, z = 0;
  friend bool operator==(const Vec3&, const Vec3&) = default;
};

struct Quat {
  double w = 1, x = 0, y = 0, z = 0;
  friend bool operator==(const Quat&, const Quat&) = default;
};

struct Pose {
  Vec3 position_m;
  Quat orientation;
};

// Pose plus its time derivative, as a scripted hand or a device reports it.
struct PoseTwist {
  Pose pose;
  Vec3 linear_velocity_m_s;
  Vec3 angular_velocity_rad_s;  // world frame
};

struct Aabb {
  Vec3 min_m;
  Vec3 max_m;
};

}  // namespace hapfluid::config
