// Conversions between WireFrame and the kernel's CAN frame structs, shared by the SocketCAN and
// loopback transports so both put the very same bytes on their wire.
#pragma once

#include <linux/can.h>
#include <linux/can/error.h>

#include <cstring>

#include "hapfluid/device/transport.hpp"

namespace hapfluid::device {

// Error frames (CAN_ERR_FLAG) become TransportErrorBits; see <linux/can/error.h>.
inline std::uint32_t can_error_bits(const can_frame& f, std::uint32_t current) {
  std::uint32_t bits = current;
  if (f.can_id & CAN_ERR_BUSOFF) bits |= kBusOff;
  if (f.can_id & CAN_ERR_RESTARTED) bits &= ~kBusOff;
  if (f.can_id & CAN_ERR_CRTL) {
    if (f.data[1] & (CAN_ERR_CRTL_RX_PASSIVE | CAN_ERR_CRTL_TX_PASSIVE)) bits |= kErrorPassive;
    if (f.data[1] & (CAN_ERR_CRTL_RX_WARNING | CAN_ERR_CRTL_TX_WARNING)) bits |= kErrorWarning;
    if (f.data[1] & (CAN_ERR_CRTL_RX_OVERFLOW | CAN_ERR_CRTL_TX_OVERFLOW)) bits |= kRxOverflow;
  }
  if (f.can_id & (CAN_ERR_PROT | CAN_ERR_ACK | CAN_ERR_BUSERROR)) bits |= kBusError;
  return bits;
}

inline void to_kernel(const WireFrame& in, canfd_frame& out) {
  std::memset(&out, 0, sizeof out);
  out.can_id = in.can_id;
  out.len = in.length;
  std::memcpy(out.data, in.data, in.length);
}

inline void from_kernel(const canfd_frame& in, bool fd, WireFrame& out) {
  out.can_id = in.can_id;
  out.fd = fd;
  out.length = in.len > (fd ? 64 : 8) ? (fd ? 64 : 8) : in.len;
  std::memcpy(out.data, in.data, out.length);
}

}  // namespace hapfluid::device
