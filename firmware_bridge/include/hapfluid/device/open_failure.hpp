// Why a transport could not open its device, decided in one place for every real transport.
//
// A device that is not there *yet* (unpowered, unplugged, its USB-CAN adapter or CAN interface
// not created) is `absent`: the transport opens anyway, reports kDisconnected (a link fault in
// the loop, zero wrench) and its reopen worker searches until the device appears, so a rig
// whose services start at boot before the arm is powered comes up by itself. Everything else is
// `permanent`: the rig file or the machine is wrong (a malformed address, no permission to an
// existing device, a kernel without the transport), waiting would hide it behind a link fault
// forever, and haptic-rt exits 2 naming the fix.
#pragma once

#include <string>

namespace hapfluid::device {

enum class OpenFailure { absent, permanent };

// One failed attempt: the class and the user-facing reason, which names the thing and the fix.
struct OpenAttempt {
  OpenFailure failure = OpenFailure::absent;
  std::string why;
};

// errno of open(2) on a device node (/dev/hidrawN) or of SIOCGIFINDEX / bind(2) on a CAN interface.
OpenFailure classify_errno(int error);
// A libusb_error code of libusb_open / libusb_claim_interface.
OpenFailure classify_libusb_error(int code);

// Reopen-worker side (never the loop thread). A device that appeared but refuses to open is
// retried there rather than fatal: udev applies the rig's access rule to a node a moment after
// the kernel creates it. A refusal that outlasts that moment (kRefusalsBeforeLog attempts in a
// row, ~1 s at the workers' 200 ms) is said once in the log, so a rule that never applies is
// named instead of hidden behind a link fault.
class RefusalLog {
 public:
  static constexpr int kRefusalsBeforeLog = 5;
  // `transport`: what to name in the line (Transport::describe()). True when it logged.
  bool note(const std::string& transport, const OpenAttempt& attempt);
  // The device opened: a refusal after its next unplug is news again.
  void clear();

 private:
  std::string last_;
  int repeats_ = 0;
  bool logged_ = false;
};

}  // namespace hapfluid::device
