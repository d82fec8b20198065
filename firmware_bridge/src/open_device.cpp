// Rig file [transport] -> transport, framing and driver.
#include "hapfluid/device/open_device.hpp"

#include <poll.h>
#include <time.h>

#include "hapfluid/device/haptic_arm.hpp"
#include "hapfluid/device/loopback.hpp"
#include "hapfluid/device/rig_fit.hpp"
#include "hapfluid/device/socketcan.hpp"
#include "hapfluid/device/spacemouse.hpp"
#include "hapfluid/device/usb_transports.hpp"

namespace hapfluid::device {

bool wait_readable(Transport& transport, int timeout_ms) {
  int fd = transport.poll_fd();
  if (fd < 0) {  // hidapi/libusb hand frames over from their own threads: nap, let the caller poll
    timespec nap{0, 1'000'000};
    nanosleep(&nap, nullptr);
    return true;
  }
  pollfd p{fd, POLLIN, 0};
  return ::poll(&p, 1, timeout_ms) > 0;
}

namespace {

LoopbackFormat loopback_format(Framing framing) {
  switch (framing) {
    case Framing::hid: return LoopbackFormat::hid;
    case Framing::bulk: return LoopbackFormat::bulk;
    default: return LoopbackFormat::can;
  }
}

std::unique_ptr<Transport> open_transport(const config::Transport& t, Framing framing, Side side) {
  switch (t.kind) {
    case config::TransportKind::loopback:
      return std::make_unique<LoopbackTransport>(t.address, side == Side::device ? LoopbackRole::bus : LoopbackRole::peer,
                                                 loopback_format(framing));
    case config::TransportKind::socketcan:
      return std::make_unique<SocketCanTransport>(t.address, t.can_fd, t.can_node_id);
    case config::TransportKind::hid:
      if (side == Side::device)
        throw TransportError("the device end of a HID transport is a USB device: haptic-fake-device presents "
                             "one through uhid (fake/uhid_transport.hpp)");
      return open_hidapi_transport(t.address);
    case config::TransportKind::usb_bulk:
      if (side == Side::device)
        throw TransportError("the device end of a USB bulk transport is a USB device: haptic-fake-device "
                             "presents one through FunctionFS (fake/functionfs_transport.hpp)");
      return open_libusb_transport(t.address);
  }
  throw TransportError("unknown transport kind");
}

Framing framing_of(const config::Transport& t) {
  switch (t.kind) {
    case config::TransportKind::loopback: return parse_framing(t.framing.c_str());
    case config::TransportKind::socketcan: return t.can_fd ? Framing::canfd : Framing::can;
    case config::TransportKind::hid: return Framing::hid;
    case config::TransportKind::usb_bulk: return Framing::bulk;
  }
  return Framing::can;
}

}  // namespace

std::unique_ptr<MessageLink> open_link(const config::Transport& t, Side side) {
  Framing framing = framing_of(t);
  return std::make_unique<MessageLink>(open_transport(t, framing, side), framing,
                                       static_cast<std::uint8_t>(t.can_node_id), side);
}

std::unique_ptr<Device> open_device(const config::RigDevice& d, RigFitCheck check) {
  try {
    if (d.kind == config::DeviceKind::spacemouse) {
      if (framing_of(d.transport) != Framing::hid)
        throw TransportError("a SpaceMouse speaks USB HID: use transport.kind = \"hid\" (or loopback with framing = \"hid\")");
      return std::make_unique<SpaceMouse>(d.name, open_transport(d.transport, Framing::hid, Side::host));
    }
    auto arm = std::make_unique<HapticArm>(d.name, open_link(d.transport, Side::host));
    // A device that answered must fit the rig; one not there yet is checked by nobody (README).
    if (check == RigFitCheck::enforce && arm->has_info())
      if (std::string misfit = rig_beyond_device(d, arm->info()); !misfit.empty()) throw TransportError(misfit);
    return arm;
  } catch (const TransportError& e) {
    throw TransportError("device '" + d.name + "' (" + config::to_string(d.transport.kind) + " " +
                         d.transport.address + "): " + e.what());
  }
}

std::string silent_device_hint(const config::RigDevice& d, const DeviceHealth& health, const std::string& rig_file) {
  const std::string what = "device '" + d.name + "' (" + config::to_string(d.transport.kind) + " " + d.transport.address + ")";
  const bool disconnected = health.transport_errors & kDisconnected;
  switch (d.transport.kind) {
    case config::TransportKind::loopback: {
      const std::string start = rig_file.empty() ? "--transport loopback --address " + d.transport.address +
                                                       " --framing " + d.transport.framing
                                                 : "--rig " + rig_file + " --device " + d.name;
      return what + " is not talking: no bus there yet; start haptic-fake-device " + start;
    }
    case config::TransportKind::socketcan:
      if (disconnected)
        return what + " is not connected: no CAN interface '" + d.transport.address + "' up yet: waiting for it " +
               "(is the CAN adapter plugged in? configure it: docs/rig-setup.md, section 6)";
      break;
    case config::TransportKind::hid:
    case config::TransportKind::usb_bulk:
      if (disconnected) return what + " is not connected: waiting for it (is it powered and plugged in?)";
      break;
  }
  return what + " is not talking: is it powered and connected?";
}

}  // namespace hapfluid::device
