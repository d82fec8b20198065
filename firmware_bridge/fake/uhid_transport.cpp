// uhid device side (see uhid_transport.hpp); every write and read checked.
#include "uhid_transport.hpp"

#include <fcntl.h>
#include <linux/uhid.h>
#include <unistd.h>

#include <cerrno>
#include <cstddef>
#include <cstring>

namespace hapfluid::fake {

namespace {

bool write_event(int fd, const uhid_event& event, std::size_t size) {
  ssize_t n = ::write(fd, &event, size);
  return n == static_cast<ssize_t>(size);
}

}  // namespace

UhidTransport::UhidTransport(const std::uint8_t* descriptor, std::size_t descriptor_size, std::uint16_t vendor,
                             std::uint16_t product, const std::string& name)
    : name_(name) {
  fd_ = ::open("/dev/uhid", O_RDWR | O_CLOEXEC | O_NONBLOCK);
  if (fd_ < 0) {
    int error = errno;
    if (error == ENOENT || error == ENODEV)
      throw device::TransportError("uhid is not available in this kernel (no /dev/uhid): load it (modprobe uhid) "
                                   "or use the loopback transport with framing = \"hid\"");
    throw device::TransportError("uhid: cannot open /dev/uhid: " + std::string(std::strerror(error)) +
                                 (error == EACCES ? " (needs root or a udev rule for /dev/uhid)" : ""));
  }
  static uhid_event event;  // ~8 KiB: keep it off the stack
  std::memset(&event, 0, sizeof event);
  event.type = UHID_CREATE2;
  std::strncpy(reinterpret_cast<char*>(event.u.create2.name), name.c_str(), sizeof event.u.create2.name - 1);
  event.u.create2.rd_size = static_cast<std::uint16_t>(descriptor_size);
  // BUS_USB, as the real arm (a USB HID device): hidapi's hidraw backend lists hidraw nodes of
  // the USB, Bluetooth, I2C and SPI buses only (0.13, Debian 12, skips BUS_VIRTUAL), so only a
  // USB one is found by the rig's VID:PID address. Its missing USB parent costs nothing but the
  // manufacturer/serial strings, which the driver does not use.
  event.u.create2.bus = 0x03;  // BUS_USB (<linux/input.h>)
  event.u.create2.vendor = vendor;
  event.u.create2.product = product;
  event.u.create2.version = 0x0100;
  std::memcpy(event.u.create2.rd_data, descriptor, descriptor_size);
  if (!write_event(fd_, event, sizeof event)) {
    int error = errno;
    ::close(fd_);
    throw device::TransportError("uhid: UHID_CREATE2 failed: " + std::string(std::strerror(error)));
  }
}

UhidTransport::~UhidTransport() {
  uhid_event event;
  std::memset(&event, 0, sizeof event);
  event.type = UHID_DESTROY;
  write_event(fd_, event, sizeof event.type);
  ::close(fd_);
}

void UhidTransport::set_feature_report(std::uint8_t report_id, const std::uint8_t* data, std::size_t size) {
  feature_id_ = report_id;
  feature_.assign(data, data + size);
}

device::Io UhidTransport::send(const device::WireFrame& frame) {
  if (!opened_) return device::Io::ok;
  uhid_event event;
  event.type = UHID_INPUT2;
  event.u.input2.size = frame.length;
  std::memcpy(event.u.input2.data, frame.data, frame.length);
  if (write_event(fd_, event, offsetof(uhid_event, u) + sizeof(std::uint16_t) + frame.length)) return device::Io::ok;
  errors_ |= device::kTxFailed;
  return device::Io::error;
}

device::Io UhidTransport::receive(device::WireFrame& frame) {
  static uhid_event event;
  for (;;) {
    ssize_t n = ::read(fd_, &event, sizeof event);
    if (n < 0) return errno == EAGAIN ? device::Io::empty : device::Io::error;
    switch (event.type) {
      case UHID_OPEN: opened_ = true; break;
      case UHID_CLOSE: opened_ = false; break;
      case UHID_STOP: opened_ = false; errors_ |= device::kDisconnected; break;
      case UHID_START: errors_ &= ~device::kDisconnected; break;
      case UHID_OUTPUT: {
        std::size_t size = event.u.output.size > sizeof frame.data ? sizeof frame.data : event.u.output.size;
        frame.can_id = 0;
        frame.fd = false;
        frame.length = static_cast<std::uint8_t>(size);
        std::memcpy(frame.data, event.u.output.data, size);
        return device::Io::ok;
      }
      case UHID_GET_REPORT: {
        uhid_event reply;
        std::memset(&reply, 0, offsetof(uhid_event, u) + sizeof reply.u.get_report_reply);
        reply.type = UHID_GET_REPORT_REPLY;
        reply.u.get_report_reply.id = event.u.get_report.id;
        if (event.u.get_report.rtype == UHID_FEATURE_REPORT && event.u.get_report.rnum == feature_id_ &&
            !feature_.empty()) {
          reply.u.get_report_reply.size = static_cast<std::uint16_t>(feature_.size());
          std::memcpy(reply.u.get_report_reply.data, feature_.data(), feature_.size());
        } else {
          reply.u.get_report_reply.err = EIO;
        }
        write_event(fd_, reply, offsetof(uhid_event, u) + sizeof reply.u.get_report_reply);
        break;
      }
      case UHID_SET_REPORT: {
        uhid_event reply;
        std::memset(&reply, 0, sizeof reply.type + sizeof reply.u.set_report_reply);
        reply.type = UHID_SET_REPORT_REPLY;
        reply.u.set_report_reply.id = event.u.set_report.id;
        reply.u.set_report_reply.err = EIO;  // commands travel as output reports, not SET_REPORT
        write_event(fd_, reply, offsetof(uhid_event, u) + sizeof reply.u.set_report_reply);
        break;
      }
      default: break;
    }
  }
}

}  // namespace hapfluid::fake
