// A one-device rig for the loop's unit tests. The test hands the loop its own Device, so the
// loopback transport named here is never opened; the shm prefix is private to the test process.
#pragma once

#include <unistd.h>

#include <string>

#include "hapfluid/config/rig.hpp"

namespace hapfluid::rt_test {

inline config::Rig one_device_rig(const std::string& device_name, const std::string& tag,
                                  int trace_ring_records = 1024) {
  config::Rig rig = config::parse_rig("[rt]\ntrace_ring_records = " + std::to_string(trace_ring_records) +
                                          "\n[[devices]]\nname = \"" + device_name +
                                          "\"\n[devices.transport]\nkind = \"loopback\"\naddress = \"/tmp/unused\"\n",
                                      tag + ".toml");
  rig.rt.shm.prefix = "hapfluid-" + tag + "-" + std::to_string(::getpid());
  return rig;
}

}  // namespace hapfluid::rt_test
