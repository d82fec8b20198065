// systemd's notify protocol (libsystemd's sd_notify over $NOTIFY_SOCKET) for Type=notify units
// with a WatchdogSec. Harmless when not under systemd: every call is a no-op. Its own library,
// hapfluid_sd_notify, so that the sim links nothing of the loop or the device drivers. Called
// from non-real-time threads only (haptic-rt's supervisor, the live sim's main thread).
#pragma once

#include <cstdint>
#include <string>

namespace hapfluid::rt {

class SdNotifier {
 public:
  SdNotifier();  // reads NOTIFY_SOCKET, WATCHDOG_USEC and WATCHDOG_PID

  bool active() const { return active_; }
  bool send(const std::string& message);   // e.g. "READY=1", "WATCHDOG=1", "STATUS=..."
  // Half of WATCHDOG_USEC (systemd's advice), 0 when the unit has no watchdog.
  std::uint64_t watchdog_ping_interval_ns() const { return watchdog_interval_ns_; }

 private:
  bool active_ = false;
  std::uint64_t watchdog_interval_ns_ = 0;
};

}  // namespace hapfluid::rt
