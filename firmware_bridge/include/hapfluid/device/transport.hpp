// A transport moves wire units (CAN frames, HID reports, USB bulk packets) between a host and a
// device without knowing what they mean. The 1 kHz loop calls send/receive only: both are
// non-blocking and allocation-free. A transport whose device I/O may block or lock (hidapi,
// libusb) does it on threads of its own and hands frames over wait-free (frame_handoff.hpp);
// the socket transports' non-blocking system calls are the loop's only device I/O. Opening a
// transport may block, allocate and throw.
#pragma once

#include <cstdint>
#include <stdexcept>
#include <string>

namespace hapfluid::device {

// Thrown when a transport cannot be opened; the message names the transport, the address and
// the fix ("SocketCAN is not available in this kernel: load can-raw and vcan").
class TransportError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// One unit on the wire. CAN: `can_id` as in <linux/can.h> (CAN_ERR_FLAG marks error frames),
// `fd` for CAN FD frames. HID: data[0] is the report id. Bulk: one transfer.
struct WireFrame {
  std::uint32_t can_id = 0;
  std::uint8_t length = 0;
  bool fd = false;
  std::uint8_t data[64] = {};
};

enum class Io { ok, empty, error };

// DeviceHealth::transport_errors bits.
enum TransportErrorBits : std::uint32_t {
  kBusOff = 1u << 0,
  kErrorPassive = 1u << 1,
  kErrorWarning = 1u << 2,
  kDisconnected = 1u << 3,
  kRxOverflow = 1u << 4,
  kTxFailed = 1u << 5,
  kBusError = 1u << 6,
};

class Transport {
 public:
  virtual ~Transport() = default;
  virtual Io send(const WireFrame& frame) = 0;
  // Error frames (CAN) are consumed here and reported through error_flags(), never returned.
  virtual Io receive(WireFrame& frame) = 0;
  // File descriptor that becomes readable when receive() may return data; -1 if none. For
  // non-real-time users (the fake device, open-time handshakes) that wait with poll().
  virtual int poll_fd() const = 0;
  virtual std::uint32_t error_flags() const = 0;
  virtual void clear_error_flags() = 0;
  // How many times the transport re-established a lost link by itself (all but the fake device's). A
  // driver restarts its sequence tracking when this changes: the device's counters moved on, or
  // restarted, while the link was down.
  virtual std::uint32_t reconnects() const { return 0; }
  virtual std::string describe() const = 0;
};

// Waits up to `timeout_ms` for poll_fd() to become readable (never use in the 1 kHz loop).
bool wait_readable(Transport& transport, int timeout_ms);

}  // namespace hapfluid::device
