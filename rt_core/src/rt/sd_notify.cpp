#include "hapfluid/rt/sd_notify.hpp"

#include <systemd/sd-daemon.h>

#include <cstdlib>

namespace hapfluid::rt {

SdNotifier::SdNotifier() : active_(std::getenv("NOTIFY_SOCKET") != nullptr) {
  std::uint64_t usec = 0;
  // > 0 only when WATCHDOG_USEC is set and WATCHDOG_PID, if set, names this process.
  if (sd_watchdog_enabled(0, &usec) > 0) watchdog_interval_ns_ = usec * 1000 / 2;
}

bool SdNotifier::send(const std::string& message) {
  return active_ && sd_notify(0, message.c_str()) > 0;
}

}  // namespace hapfluid::rt
