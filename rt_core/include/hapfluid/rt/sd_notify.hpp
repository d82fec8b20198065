// systemd's notify protocol, spoken directly over $NOTIFY_SOCKET (a datagram to a unix socket,
// '@' meaning the abstract namespace). Harmless when not under systemd: every call is a no-op.
// Used from haptic-rt's non-RT supervisor thread only.
#pragma once

#include <cstdint>
#include <string>

namespace hapfluid::rt {

class SdNotifier {
 public:
  SdNotifier();  // reads NOTIFY_SOCKET and WATCHDOG_USEC
  ~SdNotifier();
  SdNotifier(const SdNotifier&) = delete;
  SdNotifier& operator=(const SdNotifier&) = delete;

  bool active() const { return fd_ >= 0; }
  bool send(const std::string& message);   // e.g. "READY=1", "WATCHDOG=1", "STATUS=..."
  // Half of WATCHDOG_USEC (systemd's advice), 0 when the unit has no watchdog.
  std::uint64_t watchdog_ping_interval_ns() const { return watchdog_interval_ns_; }

 private:
  int fd_ = -1;
  std::string path_;
  std::uint64_t watchdog_interval_ns_ = 0;
};

}  // namespace hapfluid::rt
