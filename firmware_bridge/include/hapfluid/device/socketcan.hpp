// SocketCAN transport (CAN_RAW): classic or CAN FD frames on a kernel CAN interface, with a
// receive filter for one device node, error frames (bus-off, error-passive, ...) reported
// through error_flags(), non-blocking I/O. Fails with a clear message where the kernel lacks
// SocketCAN or the name is not a CAN interface. An interface that does not exist yet (a USB-CAN
// adapter not plugged in, systemd-networkd not run yet, a vcan created later), or that goes away,
// is reported as kDisconnected and bound by a ReopenWorker thread once it is there; an interface
// that is down keeps its socket and works again when it is up.
#pragma once

#include <string>

#include "hapfluid/device/reopen_worker.hpp"
#include "hapfluid/device/transport.hpp"

namespace hapfluid::device {

struct CanSocket;  // one bound CAN_RAW socket (socketcan.cpp)

class SocketCanTransport final : public Transport {
 public:
  // `node`: frames whose id's low 4 bits equal it are received (0: every frame, for monitors).
  SocketCanTransport(const std::string& interface, bool can_fd, unsigned node);
  ~SocketCanTransport() override;

  Io send(const WireFrame& frame) override;
  Io receive(WireFrame& frame) override;
  int poll_fd() const override;
  std::uint32_t error_flags() const override { return errors_; }
  void clear_error_flags() override { errors_ = 0; }
  std::uint32_t reconnects() const override { return reconnects_; }
  std::string describe() const override { return "SocketCAN " + interface_ + (can_fd_ ? " (CAN FD)" : ""); }

 private:
  bool adopt();
  void failed(int error, std::uint32_t otherwise);

  std::string interface_;
  bool can_fd_;
  unsigned node_;
  CanSocket* live_ = nullptr;  // owned by the loop thread; null while the interface is absent
  std::uint32_t errors_ = 0;
  std::uint32_t reconnects_ = 0;
  ReopenWorker<CanSocket> reopen_;  // last: its thread stops before anything above goes
};

}  // namespace hapfluid::device
