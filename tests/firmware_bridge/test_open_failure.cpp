// Which open errors a transport waits out and which stop haptic-rt (open_failure.hpp). A device
// absent at start must become a link fault the loop rides out until the device appears (a rig's
// services start at boot, before the arm is powered); a rig that can never work as configured
// must stop with exit 2 and the fix, or it would sit at a link fault forever with the cause
// hidden. The kernels that produce these errors are exercised in tests/hil-kernel (t_41, t_50, t_60).
#include <gtest/gtest.h>
#include <libusb-1.0/libusb.h>

#include <cerrno>

#include "hapfluid/device/open_failure.hpp"

using hapfluid::device::classify_errno;
using hapfluid::device::classify_libusb_error;
using hapfluid::device::OpenAttempt;
using hapfluid::device::OpenFailure;
using hapfluid::device::RefusalLog;

TEST(OpenFailure, ANodeOrInterfaceThatDoesNotExistYetIsAbsent) {
  EXPECT_EQ(classify_errno(ENOENT), OpenFailure::absent) << "/dev/hidrawN not created yet";
  EXPECT_EQ(classify_errno(ENODEV), OpenFailure::absent) << "SIOCGIFINDEX: no CAN interface of that name yet";
  EXPECT_EQ(classify_errno(ENXIO), OpenFailure::absent) << "a node or CAN socket whose device went away";
}

TEST(OpenFailure, ADeviceThisProcessMayNotUseIsPermanent) {
  EXPECT_EQ(classify_errno(EACCES), OpenFailure::permanent) << "no udev rule for the hapfluid group";
  EXPECT_EQ(classify_errno(EPERM), OpenFailure::permanent) << "the unit forbids the device";
  EXPECT_EQ(classify_errno(EBUSY), OpenFailure::permanent) << "another program holds the arm";
}

TEST(OpenFailure, AnErrorNotKnownToBeTransientIsReportedNotWaitedOn) {
  for (int e : {EINVAL, ENAMETOOLONG, EAFNOSUPPORT, EPROTONOSUPPORT, ENOTDIR, EIO})
    EXPECT_EQ(classify_errno(e), OpenFailure::permanent) << "errno " << e;
}

TEST(OpenFailure, LibusbWaitsOnlyForADeviceThatIsNotThere) {
  EXPECT_EQ(classify_libusb_error(LIBUSB_ERROR_NO_DEVICE), OpenFailure::absent);
  EXPECT_EQ(classify_libusb_error(LIBUSB_ERROR_ACCESS), OpenFailure::permanent) << "no udev rule";
  EXPECT_EQ(classify_libusb_error(LIBUSB_ERROR_BUSY), OpenFailure::permanent) << "interface claimed elsewhere";
  EXPECT_EQ(classify_libusb_error(LIBUSB_ERROR_NOT_FOUND), OpenFailure::permanent) << "no interface 0 on that VID:PID";
  EXPECT_EQ(classify_libusb_error(LIBUSB_ERROR_OTHER), OpenFailure::permanent);
}

TEST(OpenFailure, ARefusalIsLoggedOnceAndOnlyWhenItOutlastsUdev) {
  // udev applies the access rule a moment after the node appears: a refusal in that window is
  // not news; one that persists is said once, and again only for a new reason or a new plug-in.
  RefusalLog log;
  const OpenAttempt refused{OpenFailure::permanent, "Permission denied"};
  const OpenAttempt absent{OpenFailure::absent, "not there"};
  for (int i = 1; i < RefusalLog::kRefusalsBeforeLog; ++i) EXPECT_FALSE(log.note("t", refused)) << i;
  EXPECT_TRUE(log.note("t", refused));
  for (int i = 0; i < 20; ++i) EXPECT_FALSE(log.note("t", refused)) << "logged once";
  EXPECT_FALSE(log.note("t", absent));
  for (int i = 1; i < RefusalLog::kRefusalsBeforeLog; ++i) EXPECT_FALSE(log.note("t", refused));
  EXPECT_TRUE(log.note("t", refused)) << "unplugged and replugged: a persisting refusal is said again";
  const OpenAttempt busy{OpenFailure::permanent, "Resource busy"};
  for (int i = 1; i < RefusalLog::kRefusalsBeforeLog; ++i) EXPECT_FALSE(log.note("t", busy));
  EXPECT_TRUE(log.note("t", busy)) << "a new reason is said";
}
