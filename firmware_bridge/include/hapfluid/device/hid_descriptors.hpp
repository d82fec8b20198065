// HID report descriptors the devices present (protocol.md, "USB HID"): the hapfluid arm's
// vendor-defined 64-byte reports, and the 3Dconnexion SpaceMouse layout the SpaceMouse driver
// reads. The fake device hands these to uhid (UHID_CREATE2) in hardware-in-the-loop tests.
#pragma once

#include <cstdint>

namespace hapfluid::device {

inline constexpr std::uint8_t kHapfluidHidDescriptor[] = {
    0x06, 0x00, 0xFF,  // Usage Page (Vendor Defined 0xFF00)
    0x09, 0x01,        // Usage (hapfluid haptic arm)
    0xA1, 0x01,        // Collection (Application)
    0x15, 0x00,        //   Logical Minimum (0)
    0x26, 0xFF, 0x00,  //   Logical Maximum (255)
    0x75, 0x08,        //   Report Size (8)
    0x95, 0x3F,        //   Report Count (63): 64 bytes with the report id
    0x85, 0x01,        //   Report ID (1): device -> host packet (STATE, FAULT, INFO, heartbeat)
    0x09, 0x02,        //   Usage (0x02)
    0x81, 0x02,        //   Input (Data, Variable, Absolute)
    0x85, 0x02,        //   Report ID (2): host -> device packet (COMMAND, ESTOP, requests)
    0x09, 0x03,        //   Usage (0x03)
    0x91, 0x02,        //   Output (Data, Variable, Absolute)
    0x85, 0x03,        //   Report ID (3): INFO packet as a feature report, for tools
    0x09, 0x04,        //   Usage (0x04)
    0xB1, 0x02,        //   Feature (Data, Variable, Absolute)
    0xC0,              // End Collection
};

// 3Dconnexion SpaceMouse (classic layout): report 1 translation, report 2 rotation (int16 x3,
// logical range -350..350), report 3 buttons (16 bits).
inline constexpr std::uint8_t kSpaceMouseHidDescriptor[] = {
    0x05, 0x01,              // Usage Page (Generic Desktop)
    0x09, 0x08,              // Usage (Multi-axis Controller)
    0xA1, 0x01,              // Collection (Application)
    0xA1, 0x00,              //   Collection (Physical)
    0x85, 0x01,              //     Report ID (1)
    0x16, 0xA2, 0xFE,        //     Logical Minimum (-350)
    0x26, 0x5E, 0x01,        //     Logical Maximum (350)
    0x09, 0x30, 0x09, 0x31, 0x09, 0x32,  // Usage (X, Y, Z)
    0x75, 0x10, 0x95, 0x03,  //     Report Size (16), Report Count (3)
    0x81, 0x02,              //     Input (Data, Variable, Absolute)
    0xC0,                    //   End Collection
    0xA1, 0x00,              //   Collection (Physical)
    0x85, 0x02,              //     Report ID (2)
    0x09, 0x33, 0x09, 0x34, 0x09, 0x35,  // Usage (Rx, Ry, Rz)
    0x75, 0x10, 0x95, 0x03,  //     Report Size (16), Report Count (3)
    0x81, 0x02,              //     Input (Data, Variable, Absolute)
    0xC0,                    //   End Collection
    0xA1, 0x02,              //   Collection (Logical)
    0x85, 0x03,              //     Report ID (3)
    0x05, 0x09,              //     Usage Page (Button)
    0x19, 0x01, 0x29, 0x10,  //     Usage Minimum (1), Usage Maximum (16)
    0x15, 0x00, 0x25, 0x01,  //     Logical Minimum (0), Logical Maximum (1)
    0x75, 0x01, 0x95, 0x10,  //     Report Size (1), Report Count (16)
    0x81, 0x02,              //     Input (Data, Variable, Absolute)
    0xC0,                    //   End Collection
    0xC0,                    // End Collection
};

}  // namespace hapfluid::device
