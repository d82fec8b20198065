// The one place that maps a rig device to a Device object: firmware_bridge's driver for the rig's
// transport, or (--simulated-devices, for loop tests without a device process) an in-process
// simulated handle.
#pragma once

#include <memory>
#include <string>

#include "hapfluid/config/rig.hpp"
#include "hapfluid/device/device.hpp"

namespace hapfluid::rt {

enum class DeviceBackend { driver, simulated };

// Returns the device, or nullptr with `error` saying why and how to fix it.
std::unique_ptr<device::Device> open_rig_device(const config::RigDevice& device, DeviceBackend backend,
                                                std::string& error);

// For a device that opened but is not talking yet (not connected: absent, unplugged, its CAN
// interface not there; or connected and silent: unpowered, its fake not started): what to tell
// the user, naming the rig file in the command that starts an emulated one.
std::string silent_device_hint(const config::RigDevice& device, const device::DeviceHealth& health,
                               const std::string& rig_file);

}  // namespace hapfluid::rt
