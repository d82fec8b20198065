// Gadget HID device side (see hidg_transport.hpp); every read and write checked.
#include "hidg_transport.hpp"

#include <fcntl.h>
#include <time.h>
#include <unistd.h>

#include <cerrno>
#include <cmath>
#include <cstring>

namespace hapfluid::fake {

namespace {

std::uint64_t now_ns() {
  timespec ts;
  clock_gettime(CLOCK_MONOTONIC, &ts);
  return static_cast<std::uint64_t>(ts.tv_sec) * 1'000'000'000ull + static_cast<std::uint64_t>(ts.tv_nsec);
}

}  // namespace

HidgTransport::HidgTransport(const std::string& node, double out_interval_ms)
    : node_(node), out_interval_ns_(static_cast<std::uint64_t>(std::llround(out_interval_ms * 1e6))) {
  fd_ = ::open(node.c_str(), O_RDWR | O_NONBLOCK | O_CLOEXEC);
  if (fd_ < 0) {
    const int error = errno;
    throw device::TransportError(
        "USB gadget HID: cannot open " + node + " (" + std::strerror(error) +
        "): the kernel needs usb_f_hid, libcomposite and a UDC (dummy_hcd for tests), and a configfs gadget with "
        "a hid function whose report_desc is `haptic-fake-device --hid-report-descriptor`");
  }
}

HidgTransport::~HidgTransport() { ::close(fd_); }

device::Io HidgTransport::send(const device::WireFrame& frame) {
  if (::write(fd_, frame.data, frame.length) == frame.length) {
    errors_ &= ~device::kDisconnected;
    return device::Io::ok;
  }
  // EAGAIN: the host has not taken the last report. ESHUTDOWN: not configured by the host (yet).
  errors_ |= errno == ESHUTDOWN ? device::kDisconnected : device::kTxFailed;
  return device::Io::error;
}

device::Io HidgTransport::receive(device::WireFrame& frame) {
  if (out_interval_ns_ > 0 && !servicing_) {
    const std::uint64_t now = now_ns();
    if (now < next_service_ns_) return device::Io::empty;
    servicing_ = true;
    next_service_ns_ = now + out_interval_ns_;
  }
  const ssize_t n = ::read(fd_, frame.data, sizeof frame.data);
  if (n > 0) {
    frame.can_id = 0;
    frame.fd = false;
    frame.length = static_cast<std::uint8_t>(n);
    return device::Io::ok;
  }
  servicing_ = false;
  if (n < 0 && errno == EAGAIN) return device::Io::empty;
  errors_ |= device::kDisconnected;
  return device::Io::error;
}

}  // namespace hapfluid::fake
