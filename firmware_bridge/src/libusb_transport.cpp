// USB bulk transport over libusb's asynchronous API, driven by one I/O thread of the transport's
// own: it keeps IN transfers submitted, submits the commands the loop queued, and handles
// libusb's events (which take libusb's mutexes and make system calls), so the loop only touches
// the hand-off rings (frame_handoff.hpp). Every transfer callback runs on that thread.
//
// Transfers are torn down by libusb's rule (usb_transfer_book.hpp): stop resubmitting, cancel,
// handle events until every callback has returned, then free and close. An unplugged device is
// reported as kDisconnected and the driver recovers by itself: once the dead connection's
// transfers have all returned, a ReopenWorker thread (it never touches a live connection)
// disposes of it and opens the device again by VID:PID every 200 ms; the I/O thread adopts the
// new connection. A device absent at open starts the same way, as if it had just been unplugged.
#include <libusb-1.0/libusb.h>
#include <poll.h>
#include <sys/stat.h>
#include <pthread.h>
#include <time.h>

#include <array>
#include <atomic>
#include <cstdio>
#include <cstring>
#include <thread>

#include "hapfluid/config/log.hpp"
#include "hapfluid/device/frame_handoff.hpp"
#include "hapfluid/device/reopen_worker.hpp"
#include "hapfluid/device/usb_transfer_book.hpp"
#include "hapfluid/device/usb_transports.hpp"

namespace hapfluid::device {

namespace {

using Book = UsbTransferBook;
constexpr int kPacketBytes = 64;      // one protocol packet per transfer (protocol.md 4.5)
constexpr int kCloseLimitMs = 2000;   // cancelled transfers return within ms; this only bounds a broken stack

Book::Status status_of(libusb_transfer_status s) {
  switch (s) {
    case LIBUSB_TRANSFER_COMPLETED: return Book::Status::completed;
    case LIBUSB_TRANSFER_CANCELLED: return Book::Status::cancelled;
    case LIBUSB_TRANSFER_NO_DEVICE: return Book::Status::no_device;
    default: return Book::Status::failed;  // error, timed out, stall, overflow
  }
}

// One opened device. Each has its own libusb context: a fresh context enumerates the bus anew,
// so a replugged device is found also where no udev daemon feeds libusb's hotplug list.
struct Connection {
  libusb_context* context = nullptr;
  libusb_device_handle* handle = nullptr;
  std::uint8_t endpoint_in = kBulkEndpointIn;
  std::uint8_t endpoint_out = kBulkEndpointOut;
  std::array<libusb_transfer*, Book::kIn> in{};
  std::array<libusb_transfer*, Book::kOut> out{};
  // libusb's file descriptors (usbfs, its event and timer fds), waited on by the I/O thread.
  std::array<pollfd, 8> fds{};
  nfds_t fd_count = 0;
};

// Only once nothing of `c` is in flight (libusb would touch freed transfers otherwise).
void dispose(Connection* c) {
  if (!c) return;
  for (auto* t : c->in) libusb_free_transfer(t);
  for (auto* t : c->out) libusb_free_transfer(t);
  if (c->handle) {
    libusb_release_interface(c->handle, kBulkInterface);
    libusb_close(c->handle);
  }
  if (c->context) libusb_exit(c->context);
  delete c;
}

// The device's bulk endpoints on interface 0, from its descriptors: a gadget's UDC may assign
// other addresses than the nominal 0x01/0x81 (FunctionFS on dummy_hcd does).
void find_bulk_endpoints(Connection& c) {
  libusb_config_descriptor* config = nullptr;
  if (libusb_get_active_config_descriptor(libusb_get_device(c.handle), &config) != 0) return;
  for (int a = 0; config->bNumInterfaces > kBulkInterface && a < config->interface[kBulkInterface].num_altsetting; ++a) {
    const libusb_interface_descriptor& alt = config->interface[kBulkInterface].altsetting[a];
    for (int e = 0; e < alt.bNumEndpoints; ++e) {
      const libusb_endpoint_descriptor& ep = alt.endpoint[e];
      if ((ep.bmAttributes & LIBUSB_TRANSFER_TYPE_MASK) != LIBUSB_TRANSFER_TYPE_BULK) continue;
      if (ep.bEndpointAddress & LIBUSB_ENDPOINT_IN) c.endpoint_in = ep.bEndpointAddress;
      else c.endpoint_out = ep.bEndpointAddress;
    }
  }
  libusb_free_config_descriptor(config);
}

// The first device VID:PID on the context's bus, opened; LIBUSB_ERROR_NO_DEVICE when none is
// there, else libusb_open's own error (which tells "no permission" from "gone meanwhile").
int open_vid_pid(Connection& c, std::uint16_t vendor, std::uint16_t product) {
  libusb_device** list = nullptr;
  const ssize_t n = libusb_get_device_list(c.context, &list);
  if (n < 0) return static_cast<int>(n);
  int r = LIBUSB_ERROR_NO_DEVICE;
  for (ssize_t i = 0; i < n; ++i) {
    libusb_device_descriptor d{};
    if (libusb_get_device_descriptor(list[i], &d) != 0 || d.idVendor != vendor || d.idProduct != product) continue;
    r = libusb_open(list[i], &c.handle);
    break;
  }
  libusb_free_device_list(list, 1);  // an opened device keeps its own reference
  return r;
}

// nullptr with `attempt` filled in, `c` disposed of.
Connection* refuse(Connection* c, OpenAttempt& attempt, OpenFailure failure, const std::string& why) {
  dispose(c);
  attempt = {failure, why};
  return nullptr;
}

// Opens VID:PID and claims the bulk interface; nullptr with `attempt` naming the cause and fix.
// Blocks and allocates: the constructor and the reconnect thread only.
Connection* connect(std::uint16_t vendor, std::uint16_t product, const std::string& address, OpenAttempt& attempt) {
  auto* c = new Connection;
  int r = libusb_init(&c->context);
  if (r != 0) {
    // Permanent: libusb finds no usbfs, so this machine has no USB host for a device to appear on.
    c->context = nullptr;
    return refuse(c, attempt, OpenFailure::permanent,
                  std::string("libusb could not initialise (") + libusb_strerror(r) +
                      "): this machine exposes no USB host (no /dev/bus/usb?); use the loopback transport");
  }
  r = open_vid_pid(*c, vendor, product);
  if (r != 0)
    return refuse(c, attempt, classify_libusb_error(r),
                  "libusb: USB device " + address + " cannot be opened (" + libusb_strerror(r) +
                      "): the udev rule firmware_bridge/udev/70-hapfluid.rules must give the hapfluid group access "
                      "(docs/rig-setup.md, section 5)");
  libusb_set_auto_detach_kernel_driver(c->handle, 1);
  r = libusb_claim_interface(c->handle, kBulkInterface);
  if (r != 0)
    return refuse(c, attempt, classify_libusb_error(r),
                  "libusb: cannot claim interface 0 of " + address + ": " + libusb_strerror(r) +
                      (r == LIBUSB_ERROR_BUSY ? " (another program holds it: stop it)"
                                              : " (is the address that of a hapfluid bulk device?)"));
  find_bulk_endpoints(*c);
  for (auto& t : c->in) t = libusb_alloc_transfer(0);
  for (auto& t : c->out) t = libusb_alloc_transfer(0);
  // Fixed once the device is open and claimed: one context, one device.
  if (const libusb_pollfd** list = libusb_get_pollfds(c->context)) {
    for (const libusb_pollfd** p = list; *p && c->fd_count < c->fds.size(); ++p)
      c->fds[c->fd_count++] = {(*p)->fd, (*p)->events, 0};
    libusb_free_pollfds(list);
  }
  return c;
}

void nap_ns(long ns) {
  timespec t{0, ns};
  nanosleep(&t, nullptr);
}

class LibusbTransport final : public HandoffTransport {
 public:
  explicit LibusbTransport(const std::string& address)
      : address_(address),
        reopen_(describe(), [this](OpenAttempt& a) { return connect(vendor_, product_, address_, a); }, dispose) {
    parse_vid_pid(address, vendor_, product_);
    if (!machine_has_usb())
      throw TransportError("libusb: this machine exposes no USB (no /sys/bus/usb), so USB device " + address +
                           " can never appear: for tests load dummy_hcd and usb_f_fs, or use the loopback transport");
    for (int i = 0; i < Book::kIn; ++i) in_refs_[i] = {this, i};
    for (int i = 0; i < Book::kOut; ++i) out_refs_[i] = {this, i};
    OpenAttempt attempt;
    live_ = reopen_.first_open(attempt);
    if (!live_ && attempt.failure == OpenFailure::permanent) throw TransportError(attempt.why);
    if (live_) {
      start_streaming();
    } else {  // a link fault until it is plugged in; the I/O thread adopts what the worker opens
      book_.lose();
      raise(kDisconnected);
    }
    io_ = std::thread([this] {
      pthread_setname_np(pthread_self(), "hapfluid-usb-io");
      run();
    });
  }

  ~LibusbTransport() override {
    stop_.store(true);
    io_.join();
  }  // then reopen_ stops its thread and disposes of any connection it still holds

  std::string describe() const override { return "USB bulk (libusb) " + address_; }

 private:
  struct SlotRef {
    LibusbTransport* self = nullptr;
    int slot = 0;
  };

  // The I/O thread. Each pass: adopt a reopened connection if the last one was lost, submit what
  // the loop queued, wait for libusb's events (at most kSendPickupNs, so new commands go out
  // without the loop waking anyone), handle them (callbacks), deal with a lost device.
  void run() {
    while (!stop_.load()) {
      if (!live_) {
        discard_unsent();  // queued for the lost connection: stale by the time a device is back
        if (Connection* c = reopen_.take()) adopt(c);
        else nap_ns(10'000'000);
        continue;
      }
      submit_queued();
      timespec pickup{0, kSendPickupNs};
      ::ppoll(live_->fds.data(), live_->fd_count, &pickup, nullptr);
      timeval zero{0, 0};
      libusb_handle_events_timeout_completed(live_->context, &zero, nullptr);
      if (book_.phase() == Book::Phase::lost) retire_when_quiet();
    }
    close();
  }

  // Closing: what the loop queued last (a clean stop's zero command) goes out first, within the
  // transfers' own timeout. Then no callback resubmits; cancel what is in flight and handle events
  // until every callback has returned. Only then may the transfers be freed.
  void close() {
    if (live_ && book_.phase() == Book::Phase::streaming) {
      submit_queued();
      timeval tick{0, 10000};
      for (int waited_ms = 0; book_.out_flight() > 0 && waited_ms < kOutTimeoutMs; waited_ms += 10)
        libusb_handle_events_timeout_completed(live_->context, &tick, nullptr);
    }
    book_.begin_close();
    if (live_) {
      cancel_in_flight();
      timeval tick{0, 10000};
      for (int waited_ms = 0; !book_.quiescent() && waited_ms < kCloseLimitMs; waited_ms += 10)
        libusb_handle_events_timeout_completed(live_->context, &tick, nullptr);
    }
    if (live_ && !book_.quiescent()) {
      // Never free a transfer libusb still owns: leak this connection rather than corrupt memory.
      log::warning("libusb %s: %d IN / %d OUT transfers did not return within %d ms of cancelling; "
                   "the connection is left open", address_.c_str(), book_.in_flight(), book_.out_flight(),
                   kCloseLimitMs);
    } else {
      dispose(live_);
    }
    live_ = nullptr;
  }

  // The loop's queued frames, newest first when the device fell behind, while an OUT slot is free.
  void submit_queued() {
    for (int slot = book_.free_out_slot(); slot >= 0; slot = book_.free_out_slot()) {
      WireFrame frame;
      if (!next_to_send(frame)) return;
      std::memcpy(out_buffer_[slot], frame.data, frame.length);
      libusb_transfer* t = live_->out[slot];
      libusb_fill_bulk_transfer(t, live_->handle, live_->endpoint_out, out_buffer_[slot], frame.length,
                                &LibusbTransport::on_out, &out_refs_[slot], kOutTimeoutMs);
      const int r = libusb_submit_transfer(t);
      if (r != 0) {
        book_.submit_failed(r == LIBUSB_ERROR_NO_DEVICE);
        raise(r == LIBUSB_ERROR_NO_DEVICE ? kDisconnected : kTxFailed);
        return;
      }
      book_.submitted_out(slot);
    }
  }

  // The device is gone: the rest of the transfers end now rather than by their own errors; once
  // every callback returned, the dead connection goes to the worker, which reopens the device.
  void retire_when_quiet() {
    raise(kDisconnected);
    if (!cancelled_) {
      cancel_in_flight();
      cancelled_ = true;
    }
    if (!book_.quiescent()) return;
    reopen_.retire(live_);
    live_ = nullptr;
  }

  void start_streaming() {
    for (int i = 0; i < Book::kIn; ++i) {
      libusb_fill_bulk_transfer(live_->in[i], live_->handle, live_->endpoint_in, in_buffer_[i], kPacketBytes,
                                &LibusbTransport::on_in, &in_refs_[i], 0);
      const int r = libusb_submit_transfer(live_->in[i]);
      if (r == 0) book_.submitted_in(i);
      else book_.submit_failed(true);
    }
    if (book_.phase() == Book::Phase::lost) raise(kDisconnected);
  }

  void adopt(Connection* c) {
    live_ = c;
    book_.restart();  // lost and quiescent, checked before the old connection was retired
    cancelled_ = false;
    reconnected();
    lower(kDisconnected);
    start_streaming();
  }

  void cancel_in_flight() {
    for (int i = 0; i < Book::kIn; ++i)
      if (book_.in_busy(i)) libusb_cancel_transfer(live_->in[i]);
    for (int i = 0; i < Book::kOut; ++i)
      if (book_.out_busy(i)) libusb_cancel_transfer(live_->out[i]);
  }

  static void LIBUSB_CALL on_in(libusb_transfer* transfer) {
    const auto* ref = static_cast<const SlotRef*>(transfer->user_data);
    LibusbTransport* self = ref->self;
    const Book::InAction action = self->book_.completed_in(ref->slot, status_of(transfer->status));
    if (action.deliver && transfer->actual_length > 0) {
      WireFrame frame;
      frame.length = static_cast<std::uint8_t>(transfer->actual_length);
      std::memcpy(frame.data, transfer->buffer, frame.length);
      self->received(frame);
    }
    if (action.resubmit) {
      if (libusb_submit_transfer(transfer) == 0) self->book_.submitted_in(ref->slot);
      else self->book_.submit_failed(true);  // a bulk IN that cannot be queued: the device is unusable
    }
    if (self->book_.phase() == Book::Phase::lost) self->raise(kDisconnected);
  }

  static void LIBUSB_CALL on_out(libusb_transfer* transfer) {
    const auto* ref = static_cast<const SlotRef*>(transfer->user_data);
    LibusbTransport* self = ref->self;
    if (self->book_.completed_out(ref->slot, status_of(transfer->status))) self->raise(kTxFailed);
    if (self->book_.phase() == Book::Phase::lost) self->raise(kDisconnected);
  }

  static constexpr int kOutTimeoutMs = 100;  // a command older than this is worthless to the device

  std::string address_;
  std::uint16_t vendor_ = 0, product_ = 0;
  // The I/O thread's (the constructor's until it starts).
  Connection* live_ = nullptr;
  Book book_;
  bool cancelled_ = false;
  std::array<SlotRef, Book::kIn> in_refs_{};
  std::array<SlotRef, Book::kOut> out_refs_{};
  unsigned char in_buffer_[Book::kIn][kPacketBytes] = {};
  unsigned char out_buffer_[Book::kOut][kPacketBytes] = {};
  std::atomic<bool> stop_{false};
  std::thread io_;
  ReopenWorker<Connection> reopen_;  // last: its thread stops before anything above goes
};

}  // namespace

bool machine_has_usb() {
  struct stat st {};
  return ::stat("/sys/bus/usb", &st) == 0;
}

std::unique_ptr<Transport> open_libusb_transport(const std::string& address) {
  return std::make_unique<LibusbTransport>(address);
}

}  // namespace hapfluid::device
