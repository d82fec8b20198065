// Does a rig device's configuration fit the device that answered? The host checks the device's
// INFO reply at connect: a rig force or torque limit above the motors' own (more than one INFO
// step, 10 mN or 1 mN*m, above: INFO is rounded down) promises force the arm cannot give, and a
// device command watchdog longer than the rig's device_watchdog_ms keeps force on after a link
// loss for longer than the rig's safety case assumes.
#pragma once

#include <string>

#include "hapfluid/config/rig.hpp"
#include "hapfluid/wire/codec.h"

namespace hapfluid::device {

// "" when the rig fits; otherwise every mismatch, naming the rig key, both values and the fix.
std::string rig_beyond_device(const config::RigDevice& rig_device, const hf_info& info);

}  // namespace hapfluid::device
