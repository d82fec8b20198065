#include "hapfluid/device/rig_fit.hpp"

#include <cmath>
#include <cstdio>

namespace hapfluid::device {
namespace {
// One INFO step: a limit reported as 9.99 N may be up to 9.9999 N on the device.
constexpr double kInfoForceStepN = 0.01;
constexpr double kInfoTorqueStepNm = 0.001;

void add(std::string& all, const std::string& one) {
  if (!all.empty()) all += "; ";
  all += one;
}
}  // namespace

std::string rig_beyond_device(const config::RigDevice& d, const hf_info& info) {
  std::string problems;
  char text[320];
  const std::string key = "devices." + d.name + ".";
  if (d.limits.max_force_n > info.max_force_n + kInfoForceStepN) {
    std::snprintf(text, sizeof text,
                  "rig %smax_force_n = %g N is above the device's motor limit of %g N (its INFO reply): lower it to %g",
                  key.c_str(), d.limits.max_force_n, info.max_force_n, info.max_force_n);
    add(problems, text);
  }
  if (d.limits.max_torque_nm > info.max_torque_nm + kInfoTorqueStepNm) {
    std::snprintf(text, sizeof text,
                  "rig %smax_torque_nm = %g N*m is above the device's motor limit of %g N*m (its INFO reply): lower it "
                  "to %g",
                  key.c_str(), d.limits.max_torque_nm, info.max_torque_nm, info.max_torque_nm);
    add(problems, text);
  }
  if (double(info.watchdog_ms) > std::round(d.watchdogs.device_watchdog_ms)) {
    std::snprintf(text, sizeof text,
                  "the device's command watchdog is %u ms (its INFO reply), longer than rig %sdevice_watchdog_ms = %g: "
                  "after a link loss its motors would keep force longer than the rig assumes; set the device's "
                  "watchdog to %g ms or raise the rig key to %u",
                  unsigned(info.watchdog_ms), key.c_str(), d.watchdogs.device_watchdog_ms,
                  d.watchdogs.device_watchdog_ms, unsigned(info.watchdog_ms));
    add(problems, text);
  }
  return problems;
}

}  // namespace hapfluid::device
