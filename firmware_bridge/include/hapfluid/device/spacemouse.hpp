// 3Dconnexion SpaceMouse as an input-only 6-DoF device. The SpaceMouse is a rate controller:
// its cap deflection (HID report 1: translation x, y, z; report 2: rotation rx, ry, rz; int16
// little endian, about +-350 at full deflection; newer models send all six in report 1; report 3:
// button bitmask) is integrated into a pose inside a bounded workspace, so the 1 kHz loop sees it
// like a haptic arm that cannot push back. Axes are the SpaceMouse's own (x right, y towards the
// user, z down); the rig's workspace mapping rotates them into the scene.
#pragma once

#include <memory>
#include <string>

#include "hapfluid/device/device.hpp"
#include "hapfluid/device/transport.hpp"

namespace hapfluid::device {

struct SpaceMouseScaling {
  double full_deflection = 350.0;    // raw counts at full deflection
  double max_speed_m_s = 0.10;       // translation speed at full deflection
  double max_rate_rad_s = 1.0;       // rotation rate at full deflection
  double workspace_half_extent_m = 0.15;
};

class SpaceMouse final : public Device {
 public:
  SpaceMouse(std::string name, std::unique_ptr<Transport> transport, SpaceMouseScaling scaling = {});

  bool poll(DeviceState& out) override;
  // Input only: a zero or disabled command is accepted and does nothing; a force cannot be sent.
  bool send(const DeviceCommand& command) override;
  DeviceHealth health() const override;
  const char* name() const override { return name_.c_str(); }

 private:
  bool apply_report(const WireFrame& report);
  void integrate(double dt_s);

  std::string name_;
  std::unique_ptr<Transport> transport_;
  SpaceMouseScaling scaling_;
  DeviceState state_{};
  DeviceHealth health_{};
  double translation_raw_[3] = {0, 0, 0};
  double rotation_raw_[3] = {0, 0, 0};
  std::uint64_t last_integration_ns_ = 0;
};

}  // namespace hapfluid::device
