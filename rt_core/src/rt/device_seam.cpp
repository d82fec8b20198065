#include "hapfluid/rt/device_seam.hpp"

#include "hapfluid/rt/simulated_device.hpp"

namespace hapfluid::rt {

std::unique_ptr<device::Device> open_rig_device(const config::RigDevice& device, DeviceBackend backend,
                                                std::string& error) {
  if (backend == DeviceBackend::simulated) return std::make_unique<SimulatedDevice>(device.name);
  // MERGE SEAM: replace with `return device::open_device(device);` from firmware_bridge.
  error = "device \"" + device.name + "\": transport " + config::to_string(device.transport.kind) + " \"" +
          device.transport.address +
          "\" cannot be opened: this build has no firmware_bridge drivers; run with --simulated-devices";
  return nullptr;
}

}  // namespace hapfluid::rt
