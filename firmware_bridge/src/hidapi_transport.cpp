// HID transport over hidapi's hidraw backend: 64-byte reports, non-blocking reads.
#include <hidapi/hidapi.h>
#include <sys/stat.h>

#include <cstdio>
#include <cstring>
#include <cwchar>

#include "hapfluid/device/usb_transports.hpp"

namespace hapfluid::device {

void parse_vid_pid(const std::string& text, std::uint16_t& vendor, std::uint16_t& product) {
  unsigned v = 0, p = 0;
  char tail = 0;
  if (std::sscanf(text.c_str(), "%x:%x%c", &v, &p, &tail) != 2 || v > 0xFFFF || p > 0xFFFF)
    throw TransportError("USB address '" + text + "' is not 'vid:pid' in hex (e.g. 1209:4846)");
  vendor = static_cast<std::uint16_t>(v);
  product = static_cast<std::uint16_t>(p);
}

namespace {

std::string narrow(const wchar_t* text) {
  if (!text) return "unknown error";
  std::string out;
  for (; *text; ++text) out += *text < 128 ? static_cast<char>(*text) : '?';
  return out;
}

class HidapiTransport final : public Transport {
 public:
  explicit HidapiTransport(const std::string& address) : address_(address) {
    if (hid_init() != 0) throw TransportError("hidapi: hid_init failed: " + narrow(hid_error(nullptr)));
    struct stat st {};
    bool kernel_has_hidraw = ::stat("/sys/class/hidraw", &st) == 0;
    if (address.rfind("/dev/", 0) == 0) {
      device_ = hid_open_path(address.c_str());
    } else {
      std::uint16_t vendor = 0, product = 0;
      parse_vid_pid(address, vendor, product);
      device_ = hid_open(vendor, product, nullptr);
    }
    if (!device_) {
      if (!kernel_has_hidraw)
        throw TransportError("USB HID (hidraw) is not available in this kernel (no /sys/class/hidraw): "
                             "load hid, hidraw and uhid for tests, or use the loopback transport");
      throw TransportError("hidapi: no HID device '" + address + "' could be opened (" +
                           narrow(hid_error(nullptr)) + "): is it plugged in, and does the udev rule "
                           "firmware_bridge/udev/70-hapfluid.rules give you access to its /dev/hidraw node?");
    }
    hid_set_nonblocking(device_, 1);
  }
  ~HidapiTransport() override {
    if (device_) hid_close(device_);
  }

  Io send(const WireFrame& frame) override {
    int n = hid_write(device_, frame.data, frame.length);
    if (n >= 0) return Io::ok;
    errors_ |= kTxFailed;
    return Io::error;
  }
  Io receive(WireFrame& frame) override {
    int n = hid_read(device_, frame.data, sizeof frame.data);
    if (n == 0) return Io::empty;
    if (n < 0) {
      errors_ |= kDisconnected;
      return Io::error;
    }
    frame.can_id = 0;
    frame.fd = false;
    frame.length = static_cast<std::uint8_t>(n);
    return Io::ok;
  }
  int poll_fd() const override { return -1; }
  std::uint32_t error_flags() const override { return errors_; }
  void clear_error_flags() override { errors_ = 0; }
  std::string describe() const override { return "USB HID (hidapi) " + address_; }

 private:
  std::string address_;
  hid_device* device_ = nullptr;
  std::uint32_t errors_ = 0;
};

}  // namespace

std::unique_ptr<Transport> open_hidapi_transport(const std::string& address) {
  return std::make_unique<HidapiTransport>(address);
}

}  // namespace hapfluid::device
