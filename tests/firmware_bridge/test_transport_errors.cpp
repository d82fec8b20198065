// Transports the running kernel or machine lacks fail at open with a message naming the cause
// and the fix, never with a crash; a rig can then be fixed from the message alone. Where the
// kernel has the transport (a rig, or the QEMU guest of the HIL tests) a device that is not
// there yet is no error: it opens disconnected, named with the fix, and its transport waits for
// it (a rig's services start at boot, before the arm is powered). Which errors are which:
// open_failure.hpp and test_open_failure.cpp; the real waits: tests/hil-kernel t_41, t_50, t_60.
#include <gtest/gtest.h>

#include <string>

#include "hapfluid/config/rig.hpp"
#include "hapfluid/device/open_device.hpp"
#include "hapfluid/device/socketcan.hpp"
#include "hapfluid/device/usb_transports.hpp"

namespace {

using namespace hapfluid;

std::string open_error(const config::RigDevice& d) {
  try {
    device::open_device(d);
  } catch (const device::TransportError& e) {
    return e.what();
  }
  return "";
}

bool contains(const std::string& text, const char* part) { return text.find(part) != std::string::npos; }

config::RigDevice rig_device(const char* name, config::TransportKind kind, const char* address) {
  config::RigDevice d;
  d.name = name;
  d.transport.kind = kind;
  d.transport.address = address;
  return d;
}

// Opens `d`, which is not attached. Either the machine cannot have such a device at all (the
// error must contain `unavailable`) or the device opens disconnected and the start-up hint says
// it is waited for (returned for more checks; empty when it threw).
std::string open_absent(const config::RigDevice& d, const char* unavailable) {
  std::unique_ptr<device::Device> dev;
  try {
    dev = device::open_device(d);
  } catch (const device::TransportError& e) {
    const std::string m = e.what();
    EXPECT_TRUE(contains(m, ("device '" + d.name + "'").c_str())) << m;
    EXPECT_TRUE(contains(m, unavailable)) << "only a machine without the transport may refuse: " << m;
    return "";
  }
  const device::DeviceHealth h = dev->health();
  EXPECT_FALSE(h.connected);
  EXPECT_TRUE(h.transport_errors & device::kDisconnected) << "an absent device is a link fault";
  device::DeviceState s;
  EXPECT_FALSE(dev->poll(s));
  const bool sent = dev->send(device::DeviceCommand{});  // a SpaceMouse takes no commands: always "sent"
  if (d.kind == config::DeviceKind::haptic_arm) {
    EXPECT_FALSE(sent) << "nothing to send to";
  }
  const std::string hint = device::silent_device_hint(d, h);
  EXPECT_TRUE(contains(hint, ("device '" + d.name + "'").c_str())) << hint;
  EXPECT_TRUE(contains(hint, "is not connected: ")) << hint;
  EXPECT_TRUE(contains(hint, "waiting for it")) << hint;
  return hint;
}

TEST(TransportErrors, AMissingCanInterfaceIsWaitedForUnlessTheKernelHasNoSocketCan) {
  config::RigDevice d = rig_device("left", config::TransportKind::socketcan, "hfnope0");
  const std::string hint = open_absent(d, "SocketCAN is not available in this kernel (");
  if (!hint.empty()) {
    EXPECT_TRUE(contains(hint, "no CAN interface 'hfnope0' up yet")) << hint;
  } else {
    EXPECT_TRUE(contains(open_error(d), "vcan")) << "the message says how to get a CAN interface";
  }
}

TEST(TransportErrors, ACanInterfaceNameTheKernelCannotHaveIsRefused) {
  config::RigDevice d = rig_device("left", config::TransportKind::socketcan, "a-name-longer-than-ifnamsiz");
  const std::string m = open_error(d);
  EXPECT_TRUE(contains(m, "device 'left'") && contains(m, "too long")) << m;
}

TEST(TransportErrors, AnAbsentHidDeviceIsWaitedForUnlessTheMachineHasNoHid) {
  // No hapfluid arm is attached in CI.
  config::RigDevice d = rig_device("left", config::TransportKind::hid, "1209:4846");
  const std::string hint = open_absent(d, "not available on this machine");
  if (!hint.empty()) {
    EXPECT_EQ(hint, "device 'left' (hid 1209:4846) is not connected: waiting for it (is it powered and plugged in?)");
  }
  d.name = "mouse";
  d.kind = config::DeviceKind::spacemouse;
  d.transport.address = "256f:c635";  // a SpaceMouse Compact id; none is attached in CI
  open_absent(d, "not available on this machine");
}

TEST(TransportErrors, AHidrawPathIsWaitedForUntilItExistsButANodeThatIsNotHidrawIsRefused) {
  // A rig may name the node itself: one not created yet is an absent device (ENOENT); a node
  // that is not hidraw is the rig file's mistake and must stop haptic-rt (hidapi 0.13 crashed
  // on /dev/null).
  config::RigDevice d = rig_device("left", config::TransportKind::hid, "/dev/hidraw-hapfluid-not-created");
  open_absent(d, "not available on this machine");
  d.transport.address = "/dev/null";
  const std::string m = open_error(d);
  EXPECT_TRUE(contains(m, "device 'left'")) << m;
  EXPECT_TRUE(contains(m, "'/dev/null' is not a hidraw node") || contains(m, "not available on this machine")) << m;
}

TEST(TransportErrors, AnAbsentUsbBulkDeviceIsWaitedForUnlessTheMachineHasNoUsbHost) {
  config::RigDevice d = rig_device("arm", config::TransportKind::usb_bulk, "1209:4846");
  open_absent(d, "exposes no USB");
  const std::string m = open_error(d);
  if (!m.empty()) {
    EXPECT_TRUE(contains(m, "libusb") && contains(m, "1209:4846")) << m;
  }
}

TEST(TransportErrors, MalformedAddressesAreNamed) {
  std::uint16_t v, p;
  EXPECT_THROW(device::parse_vid_pid("12x9", v, p), device::TransportError);
  try {
    device::parse_vid_pid("1209:4846:7", v, p);
    FAIL();
  } catch (const device::TransportError& e) {
    EXPECT_TRUE(contains(e.what(), "'1209:4846:7'")) << e.what();
  }
  device::parse_vid_pid("1209:4846", v, p);
  EXPECT_EQ(v, 0x1209);
  EXPECT_EQ(p, 0x4846);
  config::RigDevice d = rig_device("arm", config::TransportKind::loopback, "/tmp/x.sock");
  d.transport.framing = "serial";
  EXPECT_TRUE(contains(open_error(d), "framing 'serial'"));
  d.transport.framing = "can";
  d.transport.can_node_id = 16;
  std::string m = open_error(d);
  EXPECT_TRUE(contains(m, "node id 16") || contains(m, "no bus")) << m;
}

TEST(TransportErrors, ASpaceMouseOnACanBusIsRefused) {
  config::RigDevice d = rig_device("mouse", config::TransportKind::socketcan, "can0");
  d.kind = config::DeviceKind::spacemouse;
  EXPECT_TRUE(contains(open_error(d), "SpaceMouse speaks USB HID"));
}

}  // namespace
