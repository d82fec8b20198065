// The libusb bulk transport's transfer bookkeeping (usb_transfer_book.hpp), without a device.
// The rules matter for safety of the whole real-time process: a transfer freed while libusb still
// owns it aborts the program (libusb's usbi_mutex_lock assertion, seen at every shutdown of a
// streaming device before this book existed), and with it the loop that commands the motors.
#include <gtest/gtest.h>

#include "hapfluid/device/usb_transfer_book.hpp"

using hapfluid::device::UsbTransferBook;
using Phase = UsbTransferBook::Phase;
using Status = UsbTransferBook::Status;

namespace {

UsbTransferBook streaming_with_all_in_submitted() {
  UsbTransferBook b;
  for (int i = 0; i < UsbTransferBook::kIn; ++i) b.submitted_in(i);
  return b;
}

}  // namespace

TEST(UsbTransferBook, StreamingDeliversAndResubmitsEveryCompletedInTransfer) {
  UsbTransferBook b = streaming_with_all_in_submitted();
  auto a = b.completed_in(2, Status::completed);
  EXPECT_TRUE(a.deliver);
  EXPECT_TRUE(a.resubmit);  // four IN transfers stay queued: a 1 kHz state stream never waits on the host
  EXPECT_FALSE(b.in_busy(2));
  b.submitted_in(2);
  EXPECT_EQ(b.in_flight(), 4);
  // A transient failure (timeout, stall, babble) keeps the queue full but delivers nothing.
  a = b.completed_in(1, Status::failed);
  EXPECT_FALSE(a.deliver);
  EXPECT_TRUE(a.resubmit);
}

// The bug this book fixes: the destructor cancelled, the callback of a transfer that completed
// meanwhile resubmitted it, and the destructor freed it in flight.
TEST(UsbTransferBook, ClosingNeverResubmitsSoCancellingEndsEveryTransfer) {
  UsbTransferBook b = streaming_with_all_in_submitted();
  b.submitted_out(0);
  b.begin_close();
  EXPECT_FALSE(b.quiescent());
  // Completions race with cancellation: data that arrived is not resubmitted (nor delivered: nobody reads).
  auto a = b.completed_in(0, Status::completed);
  EXPECT_FALSE(a.resubmit);
  EXPECT_FALSE(a.deliver);
  EXPECT_FALSE(b.completed_in(1, Status::cancelled).resubmit);
  EXPECT_FALSE(b.completed_in(2, Status::failed).resubmit);
  EXPECT_FALSE(b.quiescent()) << "IN slot 3 and the OUT transfer are still owned by libusb";
  EXPECT_FALSE(b.completed_in(3, Status::no_device).resubmit);
  EXPECT_FALSE(b.quiescent());
  EXPECT_FALSE(b.completed_out(0, Status::cancelled));
  EXPECT_TRUE(b.quiescent());  // only now may the transfers be freed and the handle closed
  EXPECT_EQ(b.phase(), Phase::closing);
  EXPECT_EQ(b.free_out_slot(), -1) << "nothing may be queued while closing";
  EXPECT_FALSE(b.restart()) << "closing is terminal";
}

TEST(UsbTransferBook, UnpluggedDeviceStopsResubmissionAndWaitsForEveryTransfer) {
  UsbTransferBook b = streaming_with_all_in_submitted();
  b.submitted_out(0);
  auto a = b.completed_in(0, Status::no_device);
  EXPECT_EQ(b.phase(), Phase::lost);
  EXPECT_FALSE(a.resubmit);
  // Transfers completing after the loss (data already on the wire) are still delivered: they are
  // real states, but the transfer is not queued again on a device that is gone.
  a = b.completed_in(1, Status::completed);
  EXPECT_TRUE(a.deliver);
  EXPECT_FALSE(a.resubmit);
  EXPECT_EQ(b.free_out_slot(), -1) << "commands are refused, not queued, while the device is gone";
  EXPECT_FALSE(b.restart()) << "a new connection must wait until the old transfers returned";
  b.completed_in(2, Status::cancelled);
  b.completed_in(3, Status::cancelled);
  EXPECT_FALSE(b.restart());
  b.completed_out(0, Status::no_device);
  ASSERT_TRUE(b.quiescent());
  EXPECT_TRUE(b.restart());  // replugged: stream again
  EXPECT_EQ(b.phase(), Phase::streaming);
  EXPECT_EQ(b.free_out_slot(), 0);
}

TEST(UsbTransferBook, FailedSubmissionOfAGoneDeviceIsALossOtherFailuresAreNot) {
  UsbTransferBook b;
  b.submit_failed(false);  // e.g. a full queue or a busy endpoint: reported as a transmit failure only
  EXPECT_EQ(b.phase(), Phase::streaming);
  b.submit_failed(true);
  EXPECT_EQ(b.phase(), Phase::lost);
  EXPECT_TRUE(b.quiescent());
}

TEST(UsbTransferBook, OneOutTransferIsInFlightAtATime) {
  // A device that does not take it keeps the newer commands in the transport's hand-off, where
  // the newest wins, rather than in the kernel's queue in order.
  UsbTransferBook b;
  ASSERT_EQ(b.free_out_slot(), 0);
  b.submitted_out(0);
  EXPECT_EQ(b.free_out_slot(), -1) << "one in flight: the device has not taken it yet";
  EXPECT_TRUE(b.completed_out(0, Status::failed)) << "a timed-out command is a transmit failure";
  EXPECT_EQ(b.free_out_slot(), 0);
  b.submitted_out(0);
  EXPECT_FALSE(b.completed_out(0, Status::completed));
  EXPECT_EQ(b.out_flight(), 0);
}
