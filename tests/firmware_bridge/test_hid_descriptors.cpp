// The HID report descriptors the devices present: a host's HID parser (hidraw, hidapi) sizes
// every report from them, so a wrong count would truncate the 38-byte STATE packet silently.
#include <gtest/gtest.h>

#include <map>

#include "hapfluid/device/hid_descriptors.hpp"
#include "hapfluid/device/usb_transports.hpp"
#include "hapfluid/wire/codec.h"

namespace {

struct Report {
  int input_bits = 0, output_bits = 0, feature_bits = 0;
};

// A minimal HID short-item walker: report id, size and count globals, main items add bits.
std::map<int, Report> walk(const std::uint8_t* d, std::size_t n, int& collections_open) {
  std::map<int, Report> reports;
  int id = 0, size = 0, count = 0;
  collections_open = 0;
  for (std::size_t i = 0; i < n;) {
    std::uint8_t prefix = d[i];
    std::size_t len = prefix & 3;
    if (len == 3) len = 4;
    std::uint32_t value = 0;
    for (std::size_t k = 0; k < len; ++k) value |= static_cast<std::uint32_t>(d[i + 1 + k]) << (8 * k);
    switch (prefix & 0xFC) {
      case 0x84: id = static_cast<int>(value); break;     // Report ID
      case 0x74: size = static_cast<int>(value); break;   // Report Size
      case 0x94: count = static_cast<int>(value); break;  // Report Count
      case 0x80: reports[id].input_bits += size * count; break;
      case 0x90: reports[id].output_bits += size * count; break;
      case 0xB0: reports[id].feature_bits += size * count; break;
      case 0xA0: ++collections_open; break;
      case 0xC0: --collections_open; break;
      default: break;
    }
    i += 1 + len;
  }
  return reports;
}

TEST(HidDescriptors, HapfluidReportsAre64BytesWithTheirIdsAndHoldTheLargestPacket) {
  int open = 0;
  auto r = walk(hapfluid::device::kHapfluidHidDescriptor, sizeof hapfluid::device::kHapfluidHidDescriptor, open);
  EXPECT_EQ(open, 0);
  const int payload_bits = (hapfluid::device::kHidReportBytes - 1) * 8;
  EXPECT_EQ(r[hapfluid::device::kHidReportDeviceToHost].input_bits, payload_bits);
  EXPECT_EQ(r[hapfluid::device::kHidReportHostToDevice].output_bits, payload_bits);
  EXPECT_EQ(r[3].feature_bits, payload_bits);
  EXPECT_GE(payload_bits / 8, static_cast<int>(HF_PACKET_MAX_BYTES));
}

TEST(HidDescriptors, SpaceMouseReportsCarryThreeAxesEachAndSixteenButtons) {
  int open = 0;
  auto r = walk(hapfluid::device::kSpaceMouseHidDescriptor, sizeof hapfluid::device::kSpaceMouseHidDescriptor, open);
  EXPECT_EQ(open, 0);
  EXPECT_EQ(r[1].input_bits, 48);  // translation x, y, z: int16 each, what SpaceMouse::apply_report reads
  EXPECT_EQ(r[2].input_bits, 48);
  EXPECT_EQ(r[3].input_bits, 16);
}

}  // namespace
