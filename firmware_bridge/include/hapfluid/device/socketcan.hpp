// SocketCAN transport (CAN_RAW): classic or CAN FD frames on a kernel CAN interface, with a
// receive filter for one device node, error frames (bus-off, error-passive, ...) reported
// through error_flags(), non-blocking I/O. Fails with a clear message where the kernel lacks
// SocketCAN or the interface does not exist.
#pragma once

#include <string>

#include "hapfluid/device/transport.hpp"

namespace hapfluid::device {

class SocketCanTransport final : public Transport {
 public:
  // `node`: frames whose id's low 4 bits equal it are received (0: every frame, for monitors).
  SocketCanTransport(const std::string& interface, bool can_fd, unsigned node);
  ~SocketCanTransport() override;

  Io send(const WireFrame& frame) override;
  Io receive(WireFrame& frame) override;
  int poll_fd() const override { return fd_; }
  std::uint32_t error_flags() const override { return errors_; }
  void clear_error_flags() override { errors_ = 0; }
  std::string describe() const override { return "SocketCAN " + interface_ + (can_fd_ ? " (CAN FD)" : ""); }

 private:
  std::string interface_;
  bool can_fd_;
  int fd_ = -1;
  std::uint32_t errors_ = 0;
};

}  // namespace hapfluid::device
