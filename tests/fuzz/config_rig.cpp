// Fuzz target: a rig file as a user writes it, through parse_rig and what haptic-rt builds from
// it at start-up (each device's safety configuration and the description it logs). Bad input
// must be a ConfigError naming the file; any other exception escaping is a bug.
#include <string>

#include "config_errors.hpp"
#include "fuzz_target.h"
#include "hapfluid/config/rig.hpp"
#include "hapfluid/safety/safety_config.hpp"

using namespace hapfluid;

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::filesystem::path file = "fuzz/rig.toml";
  try {
    const config::Rig rig = config::parse_rig(std::string(reinterpret_cast<const char*>(data), size), file);
    ++hapfluid_fuzz_accepted;
    for (const config::RigDevice& device : rig.devices)
      (void)safety::describe(safety::make_safety_config(device, rig.rt.period_ns));
  } catch (const config::ConfigError& error) {
    fuzz::check_config_error(error, file);
  }
  return 0;
}
