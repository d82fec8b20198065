// HID transport over hidapi's hidraw backend: 64-byte reports. hid_write waits until the USB
// transfer is done (the interrupt OUT endpoint's next slot, longer on a busy device), so reports
// are read and written by two threads of the transport's own, which hand frames to and from the
// loop without blocking it (frame_handoff.hpp). A device that is not there (absent at open, or
// unplugged later) is reported as kDisconnected and opened by its address (VID:PID or hidraw path)
// every 200 ms by a ReopenWorker thread; the reader thread takes it up when it appears.
#include <fcntl.h>
#include <hidapi/hidapi.h>
#include <sys/stat.h>
#include <sys/sysmacros.h>
#include <pthread.h>
#include <time.h>
#include <unistd.h>

#include <cerrno>
#include <cstdio>
#include <cstring>
#include <cwchar>
#include <mutex>
#include <thread>

#include "hapfluid/device/frame_handoff.hpp"
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
// only there, never by the I/O threads (hid_read/hid_write touch only their own handle) and
// never by the loop.
std::mutex g_hidapi_global;

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

// Opens the address; nullptr with `attempt` saying why. `vendor`/`product` are the parsed address
// unless it is a /dev path. `path` is the hidraw node opened.
hid_device* open_hid(const std::string& address, std::uint16_t vendor, std::uint16_t product, OpenAttempt& attempt,
                     std::string& path) {
  if (hid_init() != 0) {
    attempt = {OpenFailure::permanent, "hidapi: hid_init failed: " + narrow(hid_error(nullptr))};
    return nullptr;
  }
  const bool by_path = address.rfind("/dev/", 0) == 0;
  if (by_path && !check_hidraw_path(address, attempt)) return nullptr;
  path = by_path ? address : find_hid(vendor, product);
  if (path.empty()) {
    attempt = {OpenFailure::absent, "no HID device " + address + " is connected"};
    return nullptr;
  }
  if (hid_device* device = hid_open_path(path.c_str())) return device;
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

// One opened device: a handle for each I/O thread. hidapi keeps per-handle state (its error
// string) that hid_read and hid_write both rewrite, so no handle is ever used by two threads.
struct HidConnection {
  hid_device* reader = nullptr;
  hid_device* writer = nullptr;
};

void close_connection(HidConnection* c) {
  {
    std::lock_guard<std::mutex> lock(g_hidapi_global);
    if (c->reader) hid_close(c->reader);
    if (c->writer) hid_close(c->writer);
  }
  delete c;
}

// Both handles of the address, or nullptr with `attempt` saying why.
HidConnection* open_connection(const std::string& address, std::uint16_t vendor, std::uint16_t product,
                               OpenAttempt& attempt) {
  std::lock_guard<std::mutex> lock(g_hidapi_global);
  std::string path;
  hid_device* reader = open_hid(address, vendor, product, attempt, path);
  if (!reader) return nullptr;
  hid_device* writer = hid_open_path(path.c_str());
  if (!writer) {  // the node went away between the two opens: unplugged just now
    hid_close(reader);
    attempt = {OpenFailure::absent, "HID device " + address + " (" + path + ") vanished while being opened"};
    return nullptr;
  }
  return new HidConnection{reader, writer};
}

// Where no HID device can ever appear, waiting for one would hide the cause. The HID core
// registers /sys/class/hidraw when it loads, which on a rig may be only when the first HID device
// (the arm itself) is plugged in, so a missing class alone proves nothing; with no USB bus either,
// nothing will load it.
bool machine_can_have_hid() {
  struct stat st {};
  return ::stat("/sys/class/hidraw", &st) == 0 || machine_has_usb();
}

// How long the reader waits in hid_read for a report before it looks at the stop flag.
constexpr int kReadWaitMs = 50;

void nap_ns(long ns) {
  timespec t{0, ns};
  nanosleep(&t, nullptr);
}

class HidapiTransport final : public HandoffTransport {
 public:
  explicit HidapiTransport(const std::string& address)
      : address_(address),
        reopen_(describe(), [this](OpenAttempt& a) { return open_connection(address_, vendor_, product_, a); },
                close_connection) {
    if (address.rfind("/dev/", 0) != 0) parse_vid_pid(address, vendor_, product_);
    if (!machine_can_have_hid())
      throw TransportError("USB HID (hidraw) is not available on this machine (no /sys/class/hidraw, no USB): "
                           "load hid, hidraw and uhid for tests, or use the loopback transport");
    OpenAttempt attempt;
    HidConnection* first = reopen_.first_open(attempt);
    if (!first && attempt.failure == OpenFailure::permanent) throw TransportError(attempt.why);
    if (!first) raise(kDisconnected);  // a link fault until it is plugged in and the worker opens it
    writer_connection_.store(first);
    reader_ = std::thread([this, first] {
      pthread_setname_np(pthread_self(), "hapfluid-hid-rx");
      read_reports(first);
    });
    writer_ = std::thread([this] {
      pthread_setname_np(pthread_self(), "hapfluid-hid-tx");
      write_reports();
    });
  }
  // The writer first: it sends what the loop queued last (a clean stop's zero command); a write
  // in progress ends within the kernel's USB timeout (5 s) even on a device that stopped reading.
  ~HidapiTransport() override {
    stop_.store(true);
    writer_.join();
    reader_.join();
  }  // then reopen_ stops its thread and closes any connection it still holds

  std::string describe() const override { return "USB HID (hidapi) " + address_; }

 private:
  // The reader thread owns the connection: it adopts what the reopen worker opened, moves input
  // reports to the loop, and on a read error (the hidraw node went away) takes the connection
  // from the writer, waits until no write uses it, and hands it to the worker to close and reopen.
  void read_reports(HidConnection* c) {
    while (!stop_.load()) {
      if (!c) {
        c = reopen_.take();
        if (!c) {
          nap_ns(10'000'000);
          continue;
        }
        reconnected();
        writer_connection_.store(c);
        lower(kDisconnected);
      }
      WireFrame frame;
      const int n = hid_read_timeout(c->reader, frame.data, sizeof frame.data, kReadWaitMs);
      if (n > 0) {
        frame.length = static_cast<std::uint8_t>(n);
        received(frame);
        continue;
      }
      if (n == 0) continue;
      raise(kDisconnected);
      writer_connection_.store(nullptr);
      while (writing_.load() == c) nap_ns(1'000'000);  // a write on a vanished node fails at once
      reopen_.retire(c);
      c = nullptr;
    }
    if (c) {  // the writer has stopped
      writer_connection_.store(nullptr);
      close_connection(c);
    }
  }

  // The writer thread: every frame the loop queued, newest first when the device fell behind;
  // hid_write waits for the USB transfer. A connection is used only while announced in writing_
  // (and still the current one), so the reader never closes it under a write. While there is no
  // connection, whatever was queued is dropped: it would be stale by the time a device is back.
  void write_reports() {
    for (;;) {
      const bool stopping = stop_.load();
      if (HidConnection* c = writer_connection_.load()) {
        writing_.store(c);
        if (writer_connection_.load() == c) {
          WireFrame frame;
          while (next_to_send(frame))
            if (hid_write(c->writer, frame.data, frame.length) < 0) {
              raise(kTxFailed);  // a vanished device is detected by the reader
              break;
            }
        }
        writing_.store(nullptr);
      } else {
        discard_unsent();
      }
      if (stopping) return;
      // No device: nothing to pick up soon, so no need to wake 4000 times a second for it.
      nap_ns(writer_connection_.load() ? kSendPickupNs : 10'000'000);
    }
  }

  std::string address_;
  std::uint16_t vendor_ = 0, product_ = 0;  // unless address_ is a /dev path
  std::atomic<bool> stop_{false};
  std::atomic<HidConnection*> writer_connection_{nullptr};  // the connection the writer may use
  std::atomic<HidConnection*> writing_{nullptr};            // the one a write is using now
  std::thread reader_, writer_;
  ReopenWorker<HidConnection> reopen_;  // last: its thread stops before anything above goes
};

}  // namespace

std::unique_ptr<Transport> open_hidapi_transport(const std::string& address) {
  return std::make_unique<HidapiTransport>(address);
}

}  // namespace hapfluid::device
