// Bookkeeping of the libusb bulk transport's asynchronous transfers, kept apart from libusb so
// that its rules are unit-tested without a USB device (tests/firmware_bridge/test_usb_transfer_book.cpp).
//
// libusb's rule for tearing down asynchronous I/O: a transfer may be freed, and its device handle
// closed, only after its callback has returned; cancelling only *requests* the end, the callback
// comes later from the event loop; and a callback that resubmits puts the transfer back in flight.
// So closing (or losing the device) is a phase: stop resubmitting, cancel what is in flight, keep
// handling events until nothing is in flight ("quiescent"), and only then free and close.
//
//   streaming --device gone (NO_DEVICE, failed submit)--> lost --quiescent + new connection--> streaming
//   streaming / lost --destructor--> closing (terminal)
//
// No allocation, no locks: every call runs in the thread that handles libusb's events (the
// transport's I/O thread).
#pragma once

#include <array>
#include <cstdint>

namespace hapfluid::device {

class UsbTransferBook {
 public:
  static constexpr int kIn = 4;   // IN transfers kept submitted (protocol.md 4.5)
  // OUT transfers in flight at most. One: a device that falls behind takes the newest command
  // the transport's hand-off kept (frame_handoff.hpp) as soon as it takes the one in flight, not
  // a queue of older ones in the kernel. The next is submitted from the completion, so a device
  // that keeps up still gets every frame.
  static constexpr int kOut = 1;

  enum class Phase : std::uint8_t { streaming, lost, closing };
  // A finished transfer's outcome (from libusb_transfer_status; `failed` = error, timeout, stall, overflow).
  enum class Status : std::uint8_t { completed, cancelled, no_device, failed };

  struct InAction {
    bool deliver = false;   // the packet goes to the receive ring
    bool resubmit = false;  // submit the transfer again
  };

  Phase phase() const { return phase_; }
  bool in_busy(int slot) const { return in_[slot]; }
  bool out_busy(int slot) const { return out_[slot]; }
  int in_flight() const { return count(in_); }
  int out_flight() const { return count(out_); }
  // Nothing in flight: transfers may be freed and the handle closed.
  bool quiescent() const { return in_flight() == 0 && out_flight() == 0; }

  void submitted_in(int slot) { in_[slot] = true; }
  // The IN callback: the slot is no longer in flight. Data is delivered unless closing; the
  // transfer is resubmitted only while streaming, so cancellation always ends it. Resubmitting
  // after a transient failure keeps four transfers queued; if the device is gone the
  // resubmission fails and the caller reports it with submit_failed().
  InAction completed_in(int slot, Status status) {
    in_[slot] = false;
    if (status == Status::no_device) lose();
    InAction a;
    a.deliver = status == Status::completed && phase_ != Phase::closing;
    a.resubmit = phase_ == Phase::streaming && (status == Status::completed || status == Status::failed);
    return a;
  }

  // A free OUT slot for a new packet, or -1 (none free, or not streaming: nothing may be queued
  // on a device that is gone or closing).
  int free_out_slot() const {
    if (phase_ != Phase::streaming) return -1;
    for (int i = 0; i < kOut; ++i)
      if (!out_[i]) return i;
    return -1;
  }
  void submitted_out(int slot) { out_[slot] = true; }
  // The OUT callback; true when the packet was not delivered for a reason other than
  // cancellation or the device being gone (reported as a transmit failure).
  bool completed_out(int slot, Status status) {
    out_[slot] = false;
    if (status == Status::no_device) lose();
    return status == Status::failed;
  }

  // libusb_submit_transfer failed; `no_device`: LIBUSB_ERROR_NO_DEVICE (or the device is unusable).
  void submit_failed(bool no_device) {
    if (no_device) lose();
  }

  // The device is gone: stop resubmitting and queueing (the caller cancels what is in flight).
  void lose() {
    if (phase_ == Phase::streaming) phase_ = Phase::lost;
  }
  // The destructor: terminal.
  void begin_close() { phase_ = Phase::closing; }
  // A new connection replaces a lost one whose transfers all returned. False (and no change)
  // otherwise: restarting with a transfer in flight would reuse it while libusb owns it.
  bool restart() {
    if (phase_ != Phase::lost || !quiescent()) return false;
    phase_ = Phase::streaming;
    return true;
  }

 private:
  template <std::size_t N>
  static int count(const std::array<bool, N>& a) {
    int n = 0;
    for (bool b : a) n += b;
    return n;
  }
  Phase phase_ = Phase::streaming;
  std::array<bool, kIn> in_{};
  std::array<bool, kOut> out_{};
};

}  // namespace hapfluid::device
