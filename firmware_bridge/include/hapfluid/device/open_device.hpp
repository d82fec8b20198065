// The factory the 1 kHz loop calls once per rig device at start-up (not real-time: it may block
// for the device handshake, allocate and throw TransportError with a message naming the fix).
// A device that is not there yet is no error: it opens disconnected and is taken up when it
// appears; only a rig that can never work as configured throws (open_failure.hpp).
#pragma once

#include <memory>
#include <string>

#include "hapfluid/config/rig.hpp"
#include "hapfluid/device/device.hpp"
#include "hapfluid/device/message_link.hpp"

namespace hapfluid::device {

// A haptic arm that answers INFO at open must fit the rig (rig_fit.hpp), or this throws naming the
// mismatch. `skip`: a tool with no rig of its own (the probe given only an address) reports the
// device's INFO instead.
enum class RigFitCheck { enforce, skip };
std::unique_ptr<Device> open_device(const config::RigDevice& rig_device, RigFitCheck check = RigFitCheck::enforce);

// What to tell the user about a device that opened but stayed silent through the handshake
// (health().connected false): not connected (kDisconnected: no USB device, CAN interface or
// loopback bus there yet; its transport waits for it), or connected but not talking (unpowered
// on its CAN bus). `rig_file`, when known, goes into the command that starts a fake device.
std::string silent_device_hint(const config::RigDevice& rig_device, const DeviceHealth& health,
                               const std::string& rig_file = "");

// The transport and framing a rig device's [transport] table asks for, on the given side
// (the fake device opens the device side of the same description).
std::unique_ptr<MessageLink> open_link(const config::Transport& transport, Side side);

}  // namespace hapfluid::device
