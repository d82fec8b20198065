// USB transports: HID reports through hidapi (hidraw backend) and bulk transfers through libusb
// (asynchronous transfers serviced without blocking). Both fail with a clear message where the
// machine can have no such device, and wait for one that is not plugged in yet.
#pragma once

#include <cstdint>
#include <memory>
#include <string>

#include "hapfluid/device/transport.hpp"

namespace hapfluid::device {

// USB identity of hapfluid devices (pid.codes open-source VID) and the bulk interface layout.
inline constexpr std::uint16_t kHapfluidVendorId = 0x1209;
inline constexpr std::uint16_t kHapfluidProductId = 0x4846;
inline constexpr std::uint8_t kBulkInterface = 0;
inline constexpr std::uint8_t kBulkEndpointOut = 0x01;
inline constexpr std::uint8_t kBulkEndpointIn = 0x81;

// HID report ids (see protocol.md, "USB HID"): input reports carry device->host packets,
// output reports host->device packets; every report is 64 bytes including its id.
inline constexpr std::uint8_t kHidReportDeviceToHost = 0x01;
inline constexpr std::uint8_t kHidReportHostToDevice = 0x02;
inline constexpr std::size_t kHidReportBytes = 64;

// Whether a USB device can ever appear here: /sys/bus/usb exists once usbcore runs, which on a
// rig is from boot (its host controllers). Where it does not (a container, a CI machine), an
// absent USB device is refused rather than waited for: nothing would ever plug in.
bool machine_has_usb();

// "1209:4846" -> {0x1209, 0x4846}; throws TransportError naming the text otherwise.
void parse_vid_pid(const std::string& text, std::uint16_t& vendor, std::uint16_t& product);

// address: "vid:pid" or a /dev/hidrawN path.
std::unique_ptr<Transport> open_hidapi_transport(const std::string& address);
// address: "vid:pid".
std::unique_ptr<Transport> open_libusb_transport(const std::string& address);

}  // namespace hapfluid::device
