// Device side of USB HID on a real USB link: the fake device drives the HID function of a USB
// gadget (configfs `hid` function, usb_f_hid; on dummy_hcd in the hardware-in-the-loop guest)
// through its /dev/hidgN node. The host then has what a rig has: usbhid, a hidraw node whose
// writes are interrupt OUT transfers that hid_write waits for, and hidapi on top (unlike uhid,
// where an output report is only queued). The gadget (VID:PID, the report descriptor of
// hid_descriptors.hpp, 64-byte reports, UDC binding) is set up through configfs by whoever creates
// it; this class moves reports. Elsewhere opening fails with a message naming the missing piece.
#pragma once

#include <cstdint>
#include <string>

#include "hapfluid/device/transport.hpp"

namespace hapfluid::fake {

class HidgTransport final : public device::Transport {
 public:
  // `out_interval_ms` > 0 makes a slow device: it takes the output reports its endpoint buffered
  // only every that many milliseconds, so in between the host's writes wait for it.
  HidgTransport(const std::string& node, double out_interval_ms);
  ~HidgTransport() override;

  // Input reports (data[0] = report id). One at a time: while the host has not taken the last one
  // the report is dropped (Io::error, kTxFailed), as an IN endpoint with a full buffer would.
  device::Io send(const device::WireFrame& frame) override;
  // Output reports (data[0] = report id).
  device::Io receive(device::WireFrame& frame) override;
  int poll_fd() const override { return fd_; }
  std::uint32_t error_flags() const override { return errors_; }
  void clear_error_flags() override { errors_ = 0; }
  std::string describe() const override { return "USB gadget HID " + node_; }

 private:
  int fd_ = -1;
  std::string node_;
  std::uint64_t out_interval_ns_ = 0;
  std::uint64_t next_service_ns_ = 0;
  bool servicing_ = false;  // taking what the endpoint buffered, until it is empty
  std::uint32_t errors_ = 0;
};

}  // namespace hapfluid::fake
