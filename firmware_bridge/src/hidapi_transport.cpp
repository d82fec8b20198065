// HID transport over hidapi's hidraw backend: 64-byte reports, non-blocking reads. A device that
// is not there (absent at open, or unplugged later) is reported as kDisconnected and opened by its
// address (VID:PID or hidraw path) every 200 ms by a ReopenWorker thread, so the same driver
// takes it up when it appears without the loop blocking on hid_open.
#include <fcntl.h>
#include <hidapi/hidapi.h>
#include <sys/stat.h>
#include <sys/sysmacros.h>
#include <unistd.h>

#include <cerrno>
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

// The hidraw node of the first HID device VID:PID hidapi lists, or "" when none is there.
std::string find_hid(std::uint16_t vendor, std::uint16_t product) {
  hid_device_info* list = hid_enumerate(vendor, product);
  std::string path = list && list->path ? list->path : "";
  hid_free_enumeration(list);
  return path;
}

// Whether the character device `node` is a hidraw node: its sysfs entry's subsystem is hidraw
// (whatever the /dev name, e.g. a udev symlink).
bool is_hidraw(dev_t node) {
  char link[64];
  std::snprintf(link, sizeof link, "/sys/dev/char/%u:%u/subsystem", major(node), minor(node));
  char target[256];
  const ssize_t n = ::readlink(link, target, sizeof target - 1);
  if (n <= 0) return false;
  target[n] = 0;
  const char* base = std::strrchr(target, '/');
  return base && std::strcmp(base + 1, "hidraw") == 0;
}

// A /dev address, checked before hidapi sees it: hid_open_path (hidapi 0.13) frees an unset
// pointer and crashes when the node is not hidraw (/dev/null did, in
// tests/firmware_bridge/test_transport_errors.cpp). False with `attempt` saying why.
bool check_hidraw_path(const std::string& path, OpenAttempt& attempt) {
  struct stat st {};
  if (::stat(path.c_str(), &st) != 0) {
    const int error = errno;  // ENOENT: not created yet (the device enumerates later)
    attempt = {classify_errno(error), "hidapi: " + path + ": " + std::strerror(error)};
    return false;
  }
  if (S_ISCHR(st.st_mode) && is_hidraw(st.st_rdev)) return true;
  attempt = {OpenFailure::permanent,
             "'" + path + "' is not a hidraw node: fix transport.address in the rig file (\"vid:pid\" or /dev/hidrawN)"};
  return false;
}

// Opens the address non-blocking; nullptr with `attempt` saying why. `vendor`/`product` are the
// parsed address unless it is a /dev path.
hid_device* open_hid(const std::string& address, std::uint16_t vendor, std::uint16_t product, OpenAttempt& attempt) {
  std::lock_guard<std::mutex> lock(g_hidapi_global);
  if (hid_init() != 0) {
    attempt = {OpenFailure::permanent, "hidapi: hid_init failed: " + narrow(hid_error(nullptr))};
    return nullptr;
  }
  const bool by_path = address.rfind("/dev/", 0) == 0;
  if (by_path && !check_hidraw_path(address, attempt)) return nullptr;
  const std::string path = by_path ? address : find_hid(vendor, product);
  if (path.empty()) {
    attempt = {OpenFailure::absent, "no HID device " + address + " is connected"};
    return nullptr;
  }
  if (hid_device* device = hid_open_path(path.c_str())) {
    hid_set_nonblocking(device, 1);
    return device;
  }
  // hidapi keeps only a text; opening the node ourselves gives the errno that tells a node that
  // is not (or no longer) there from one this process may not open (open_failure.hpp).
  const int fd = ::open(path.c_str(), O_RDWR | O_CLOEXEC);
  const int error = errno;
  if (fd >= 0) {
    ::close(fd);
    attempt = {OpenFailure::permanent, "'" + path + "' opens but is not a HID device hidapi can use (" +
                                           narrow(hid_error(nullptr)) + "): fix transport.address in the rig file"};
    return nullptr;
  }
  attempt.failure = classify_errno(error);
  attempt.why = "hidapi: HID device " + address + (by_path ? "" : " (" + path + ")") + " cannot be opened: " +
                std::strerror(error) +
                ": the udev rule firmware_bridge/udev/70-hapfluid.rules must give the hapfluid group access to "
                "its /dev/hidraw node (docs/rig-setup.md, section 5)";
  return nullptr;
}

// Where no HID device can ever appear, waiting for one would hide the cause. The HID core
// registers /sys/class/hidraw when it loads, which on a rig may be only when the first HID device
// (the arm itself) is plugged in, so a missing class alone proves nothing; with no USB bus either,
// nothing will load it.
bool machine_can_have_hid() {
  struct stat st {};
  return ::stat("/sys/class/hidraw", &st) == 0 || machine_has_usb();
}

class HidapiTransport final : public Transport {
 public:
  explicit HidapiTransport(const std::string& address)
      : address_(address),
        reopen_(describe(), [this](OpenAttempt& a) { return open_hid(address_, vendor_, product_, a); }, close_hid) {
    if (address.rfind("/dev/", 0) != 0) parse_vid_pid(address, vendor_, product_);
    if (!machine_can_have_hid())
      throw TransportError("USB HID (hidraw) is not available on this machine (no /sys/class/hidraw, no USB): "
                           "load hid, hidraw and uhid for tests, or use the loopback transport");
    OpenAttempt attempt;
    device_ = reopen_.first_open(attempt);
    if (!device_ && attempt.failure == OpenFailure::permanent) throw TransportError(attempt.why);
    if (!device_) errors_ |= kDisconnected;  // a link fault until it is plugged in and the worker opens it
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
  std::uint16_t vendor_ = 0, product_ = 0;  // unless address_ is a /dev path
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
