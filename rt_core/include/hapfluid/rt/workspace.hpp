// The rig's workspace mapping between a device's frame and the scene (config::WorkspaceMapping):
//   x_scene = offset + scale * R * x_device,  v_scene = scale * R * v_device,
//   q_scene = R * q_device,                   w_scene = R * w_device,
// and wrenches back: F_device = force_scale * R^-1 F_scene, tau_device = force_scale * R^-1 tau_scene.
// Stiffness and damping seen by the hand therefore scale by force_scale * scale (linear) and by
// force_scale (angular); the coupling-mode caps divide the rig's device caps by those factors.
#pragma once

#include "hapfluid/config/rig.hpp"
#include "hapfluid/safety/wrench.hpp"

namespace hapfluid::rt {

using safety::Quat;
using safety::V3;
using safety::Wrench;

struct Twist6 {
  V3 position_m;
  Quat orientation;
  V3 linear_velocity_m_s;
  V3 angular_velocity_rad_s;
};

class Workspace {
 public:
  explicit Workspace(const config::WorkspaceMapping& m)
      : offset_{m.offset_m.x, m.offset_m.y, m.offset_m.z},
        rotation_(safety::normalized({m.rotation.w, m.rotation.x, m.rotation.y, m.rotation.z})),
        scale_(m.scale),
        force_scale_(m.force_scale) {}

  Twist6 to_scene(const Twist6& d) const {
    return {offset_ + scale_ * safety::rotate(rotation_, d.position_m), rotation_ * d.orientation,
            scale_ * safety::rotate(rotation_, d.linear_velocity_m_s), safety::rotate(rotation_, d.angular_velocity_rad_s)};
  }
  Wrench to_device(const Wrench& scene) const {
    Quat inverse = safety::conjugate(rotation_);
    return {force_scale_ * safety::rotate(inverse, scene.force_n), force_scale_ * safety::rotate(inverse, scene.torque_nm)};
  }
  Wrench to_scene(const Wrench& device) const {
    return {(1.0 / force_scale_) * safety::rotate(rotation_, device.force_n),
            (1.0 / force_scale_) * safety::rotate(rotation_, device.torque_nm)};
  }
  double linear_gain() const { return force_scale_ * scale_; }  // scene N/m -> device N/m
  double angular_gain() const { return force_scale_; }

 private:
  V3 offset_;
  Quat rotation_;
  double scale_;
  double force_scale_;
};

}  // namespace hapfluid::rt
