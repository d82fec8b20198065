// HID transport over hidapi's hidraw backend: 64-byte reports, non-blocking reads. An unplugged
// device is reported as kDisconnected and reopened by its address (VID:PID or hidraw path) every
// 200 ms by a ReopenWorker thread, so the same driver recovers after a replug without the loop
// blocking on hid_open.
#include <hidapi/hidapi.h>
#include <sys/stat.h>

#include <cstdio>
#include <cstring>
#include <cwchar>
#include <mutex>

#include "hapfluid/device/reopen_worker.hpp"
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

// hidapi keeps global state (its init flag, the global error string) that hid_open, hid_init and
// hid_close touch; reopen threads of several devices and a constructor may run at once. Held
// only there, never by the loop (hid_read/hid_write touch only their own device).
std::mutex g_hidapi_global;

void close_hid(hid_device* device) {
  std::lock_guard<std::mutex> lock(g_hidapi_global);
  hid_close(device);
}

// Opens the address non-blocking; nullptr if no such device is there.
hid_device* open_hid(const std::string& address) {
  std::lock_guard<std::mutex> lock(g_hidapi_global);
  if (hid_init() != 0) return nullptr;
  hid_device* device = nullptr;
  if (address.rfind("/dev/", 0) == 0) {
    device = hid_open_path(address.c_str());
  } else {
    std::uint16_t vendor = 0, product = 0;
    parse_vid_pid(address, vendor, product);
    device = hid_open(vendor, product, nullptr);
  }
  if (device) hid_set_nonblocking(device, 1);
  return device;
}

class HidapiTransport final : public Transport {
 public:
  explicit HidapiTransport(const std::string& address)
      : address_(address), reopen_([this] { return open_hid(address_); }, close_hid) {
    {
      std::lock_guard<std::mutex> lock(g_hidapi_global);
      if (hid_init() != 0) throw TransportError("hidapi: hid_init failed: " + narrow(hid_error(nullptr)));
    }
    struct stat st {};
    bool kernel_has_hidraw = ::stat("/sys/class/hidraw", &st) == 0;
    device_ = open_hid(address);
    if (!device_) {
      std::lock_guard<std::mutex> lock(g_hidapi_global);  // hid_error(nullptr) reads the global error
      if (!kernel_has_hidraw)
        throw TransportError("USB HID (hidraw) is not available in this kernel (no /sys/class/hidraw): "
                             "load hid, hidraw and uhid for tests, or use the loopback transport");
      throw TransportError("hidapi: no HID device '" + address + "' could be opened (" +
                           narrow(hid_error(nullptr)) + "): is it plugged in, and does the udev rule "
                           "firmware_bridge/udev/70-hapfluid.rules give you access to its /dev/hidraw node?");
    }
  }
  ~HidapiTransport() override {
    if (device_) close_hid(device_);
  }  // then reopen_ stops its thread and closes any device it still holds

  Io send(const WireFrame& frame) override {
    if (!device_ && !adopt()) return Io::error;  // gone: kDisconnected is set
    int n = hid_write(device_, frame.data, frame.length);
    if (n >= 0) return Io::ok;
    errors_ |= kTxFailed;  // a vanished device is detected by receive()
    return Io::error;
  }
  Io receive(WireFrame& frame) override {
    if (!device_ && !adopt()) return Io::error;
    int n = hid_read(device_, frame.data, sizeof frame.data);
    if (n == 0) return Io::empty;
    if (n < 0) {  // the hidraw node went away: hand the dead handle over, reopen in the background
      errors_ |= kDisconnected;
      reopen_.retire(device_);
      device_ = nullptr;
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
  std::uint32_t reconnects() const override { return reconnects_; }
  std::string describe() const override { return "USB HID (hidapi) " + address_; }

 private:
  bool adopt() {
    device_ = reopen_.take();
    if (!device_) return false;
    errors_ &= ~kDisconnected;
    ++reconnects_;
    return true;
  }

  std::string address_;
  hid_device* device_ = nullptr;
  std::uint32_t errors_ = 0;
  std::uint32_t reconnects_ = 0;
  ReopenWorker<hid_device> reopen_;  // last: its thread stops before anything above goes
};

}  // namespace

std::unique_ptr<Transport> open_hidapi_transport(const std::string& address) {
  return std::make_unique<HidapiTransport>(address);
}

}  // namespace hapfluid::device
