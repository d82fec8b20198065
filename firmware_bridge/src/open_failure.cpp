// The one table of which open errors mean "not there yet" and which mean "never, as configured".
#include "hapfluid/config/log.hpp"
#include "hapfluid/device/open_failure.hpp"

#include <libusb-1.0/libusb.h>

#include <cerrno>
#include <cstdio>

namespace hapfluid::device {

OpenFailure classify_errno(int error) {
  switch (error) {
    // ENOENT: no such node yet (/dev/hidrawN appears when the device enumerates).
    // ENODEV: no such device: SIOCGIFINDEX finds no interface of that name (a USB-CAN adapter
    //   unplugged, systemd-networkd or `ip link add` not run yet), or it went away before bind.
    // ENXIO: a node or socket whose device is gone (a stale /dev node after an unplug; a CAN
    //   socket the kernel unbound when its interface was removed).
    // All three change by themselves when the device is plugged in, powered or created.
    case ENOENT:
    case ENODEV:
    case ENXIO:
      return OpenFailure::absent;
    // EACCES / EPERM: the device is there and this process may not use it (no udev rule for the
    //   hapfluid group, a unit without DeviceAllow or with AF_CAN restricted): it stays so until
    //   an administrator changes the rig. EBUSY: another program holds it exclusively; two
    //   programs commanding one arm is a configuration error, not a wait.
    // Anything else is unknown here and is reported rather than waited on.
    default:
      return OpenFailure::permanent;
  }
}

OpenFailure classify_libusb_error(int code) {
  // NO_DEVICE: unplugged between enumeration and open/claim, like ENODEV. ACCESS (no udev rule),
  // BUSY (another program claimed interface 0), NOT_FOUND (the VID:PID has no interface 0: not
  // a hapfluid bulk device) and the rest are the rig's to fix.
  return code == LIBUSB_ERROR_NO_DEVICE ? OpenFailure::absent : OpenFailure::permanent;
}

void RefusalLog::clear() {
  last_.clear();
  repeats_ = 0;
  logged_ = false;
}

bool RefusalLog::note(const std::string& transport, const OpenAttempt& attempt) {
  if (attempt.failure != OpenFailure::permanent) {  // absent again: a later refusal is news
    clear();
    return false;
  }
  if (attempt.why != last_) {
    clear();
    last_ = attempt.why;
  }
  if (logged_ || ++repeats_ < kRefusalsBeforeLog) return false;
  log::warning("%s: the device is there but does not open: %s (still trying)", transport.c_str(),
               attempt.why.c_str());
  logged_ = true;
  return true;
}

}  // namespace hapfluid::device
