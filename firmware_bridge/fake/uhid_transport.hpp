// Device side of USB HID without USB: the fake device creates a HID device through /dev/uhid
// (UHID_CREATE2 with the project's report descriptor), so the host's hidapi driver opens a real
// /dev/hidrawN exactly as on a rig. Needs a kernel with uhid (the hardware-in-the-loop guest);
// elsewhere opening fails with a message saying so.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "hapfluid/device/transport.hpp"

namespace hapfluid::fake {

class UhidTransport final : public device::Transport {
 public:
  UhidTransport(const std::uint8_t* descriptor, std::size_t descriptor_size, std::uint16_t vendor,
                std::uint16_t product, const std::string& name);
  ~UhidTransport() override;

  // Input reports (data[0] = report id). Before the host opens the hidraw node nobody listens:
  // the report is dropped and Io::ok returned, as a USB device's interrupt IN would be ignored.
  device::Io send(const device::WireFrame& frame) override;
  // Output reports from the host (data[0] = report id); kernel events are handled on the way.
  device::Io receive(device::WireFrame& frame) override;
  int poll_fd() const override { return fd_; }
  std::uint32_t error_flags() const override { return errors_; }
  void clear_error_flags() override { errors_ = 0; }
  std::string describe() const override { return "uhid " + name_; }

  // The bytes answered to a GET_FEATURE of `report_id` (e.g. the INFO packet for report 3).
  void set_feature_report(std::uint8_t report_id, const std::uint8_t* data, std::size_t size);
  bool host_opened() const { return opened_; }

 private:
  int fd_ = -1;
  std::string name_;
  bool opened_ = false;
  std::uint32_t errors_ = 0;
  std::uint8_t feature_id_ = 0;
  std::vector<std::uint8_t> feature_;
};

}  // namespace hapfluid::fake
