// Transports the running kernel or machine lacks fail at open with a message naming the cause
// and the fix, never with a crash; a rig can then be fixed from the message alone. Where the
// kernel has the transport (a rig, or the QEMU guest of the HIL tests) the same calls succeed or
// name the missing interface/device.
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

TEST(TransportErrors, SocketCanNamesTheMissingKernelSupportOrInterface) {
  config::RigDevice d;
  d.name = "left";
  d.transport.kind = config::TransportKind::socketcan;
  d.transport.address = "hfnope0";
  std::string m = open_error(d);
  ASSERT_FALSE(m.empty());
  EXPECT_TRUE(contains(m, "device 'left'")) << m;
  EXPECT_TRUE(contains(m, "SocketCAN is not available in this kernel: ") ||
              contains(m, "SocketCAN is not available in this kernel (") ||
              contains(m, "no CAN interface 'hfnope0'")) << m;
  EXPECT_TRUE(contains(m, "vcan")) << "the message says how to get a CAN interface: " << m;
}

TEST(TransportErrors, HidNamesTheDeviceAndTheFix) {
  config::RigDevice d;
  d.name = "mouse";
  d.kind = config::DeviceKind::spacemouse;
  d.transport.kind = config::TransportKind::hid;
  d.transport.address = "256f:c635";  // a SpaceMouse Compact id; none is attached in CI
  std::string m = open_error(d);
  ASSERT_FALSE(m.empty()) << "no such HID device on a CI machine";
  EXPECT_TRUE(contains(m, "hidraw") || contains(m, "no HID device")) << m;
}

TEST(TransportErrors, UsbBulkNamesTheDeviceAndTheFix) {
  config::RigDevice d;
  d.name = "arm";
  d.transport.kind = config::TransportKind::usb_bulk;
  d.transport.address = "1209:4846";
  std::string m = open_error(d);
  ASSERT_FALSE(m.empty()) << "no hapfluid USB device on a CI machine";
  EXPECT_TRUE(contains(m, "libusb")) << m;
  EXPECT_TRUE(contains(m, "1209:4846")) << m;
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
  config::RigDevice d;
  d.name = "arm";
  d.transport.kind = config::TransportKind::loopback;
  d.transport.address = "/tmp/x.sock";
  d.transport.framing = "serial";
  EXPECT_TRUE(contains(open_error(d), "framing 'serial'"));
  d.transport.framing = "can";
  d.transport.can_node_id = 16;
  std::string m = open_error(d);
  EXPECT_TRUE(contains(m, "node id 16") || contains(m, "no bus")) << m;
}

TEST(TransportErrors, ASpaceMouseOnACanBusIsRefused) {
  config::RigDevice d;
  d.name = "mouse";
  d.kind = config::DeviceKind::spacemouse;
  d.transport.kind = config::TransportKind::socketcan;
  d.transport.address = "can0";
  EXPECT_TRUE(contains(open_error(d), "SpaceMouse speaks USB HID"));
}

}  // namespace
