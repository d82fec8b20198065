#include "hapfluid/rt/device_seam.hpp"

#include "hapfluid/device/open_device.hpp"
#include "hapfluid/device/transport.hpp"
#include "hapfluid/rt/simulated_device.hpp"

namespace hapfluid::rt {

std::unique_ptr<device::Device> open_rig_device(const config::RigDevice& device, DeviceBackend backend,
                                                std::string& error) {
  if (backend == DeviceBackend::simulated) return std::make_unique<SimulatedDevice>(device.name);
  // The real driver for the rig's transport (CAN, HID, USB bulk, loopback). Opening may block
  // for the device's handshake: this runs once at start-up, before the loop.
  try {
    return device::open_device(device);
  } catch (const std::exception& e) {
    error = e.what();  // names the device, its transport and the fix
    return nullptr;
  }
}

std::string silent_device_hint(const config::RigDevice& device, const device::DeviceHealth& health,
                               const std::string& rig_file) {
  return device::silent_device_hint(device, health, rig_file);
}

}  // namespace hapfluid::rt
