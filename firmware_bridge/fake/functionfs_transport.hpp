// Device side of USB bulk without hardware: the fake device serves a FunctionFS function (bulk IN
// and OUT on one vendor-class interface) in a USB gadget, e.g. on dummy_hcd in the
// hardware-in-the-loop guest, so the host's libusb driver opens a real USB device by VID:PID.
// The gadget itself (VID:PID 1209:4846, configuration, UDC binding) is set up through configfs by
// whoever mounts FunctionFS; this class writes the descriptors to ep0 and moves packets.
// Endpoint file I/O blocks (endpoint files have no poll() and no non-blocking transfers), so a
// reader and a writer thread feed queues; the fake device is not the real-time loop. The
// destructor interrupts a transfer blocked on a host that stopped reading with a thread-directed
// SIGUSR2 (handler installed without SA_RESTART: the call returns EINTR) and joins both threads,
// so SIGTERM always ends the program. Elsewhere opening fails with a message naming the missing piece.
#pragma once

#include <memory>
#include <string>

#include "hapfluid/device/transport.hpp"

namespace hapfluid::fake {

class FunctionFsTransport final : public device::Transport {
 public:
  // `out_interval_ms` > 0 makes a slow device: it takes one OUT packet every that many
  // milliseconds, so in between the host's transfers wait for it.
  FunctionFsTransport(const std::string& mount_dir, double out_interval_ms = 0);
  ~FunctionFsTransport() override;

  device::Io send(const device::WireFrame& frame) override;     // queued; dropped when 64 are pending
  device::Io receive(device::WireFrame& frame) override;        // also handles ep0 events
  int poll_fd() const override;
  std::uint32_t error_flags() const override;
  void clear_error_flags() override;
  std::string describe() const override { return "FunctionFS " + mount_dir_; }

  struct Shared;

 private:
  void service_ep0();
  std::string mount_dir_;
  std::shared_ptr<Shared> shared_;
};

}  // namespace hapfluid::fake
