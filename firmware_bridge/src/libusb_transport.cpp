// USB bulk transport over libusb's asynchronous API: IN transfers stay submitted, completions
// land in a small ring during service(), which polls libusb's events with a zero timeout: no
// thread, no busy wait, no blocking call in the 1 kHz loop.
#include <libusb-1.0/libusb.h>
#include <sys/stat.h>

#include <array>
#include <cstring>

#include "hapfluid/device/usb_transports.hpp"

namespace hapfluid::device {

namespace {

constexpr int kInTransfers = 4;
constexpr int kOutTransfers = 8;
constexpr int kRing = 64;  // packets; 64 ms of state at 1 kHz

class LibusbTransport final : public Transport {
 public:
  explicit LibusbTransport(const std::string& address) : address_(address) {
    std::uint16_t vendor = 0, product = 0;
    parse_vid_pid(address, vendor, product);
    int r = libusb_init(&context_);
    if (r != 0)
      throw TransportError(std::string("libusb could not initialise (") + libusb_strerror(r) +
                           "): this machine exposes no USB host (no /dev/bus/usb?); use the loopback transport");
    handle_ = libusb_open_device_with_vid_pid(context_, vendor, product);
    if (!handle_) {
      struct stat st {};
      std::string why = ::stat("/dev/bus/usb", &st) == 0
                            ? "is it plugged in, and does the udev rule firmware_bridge/udev/70-hapfluid.rules "
                              "give you access?"
                            : "this kernel exposes no USB devices (no /dev/bus/usb); for tests load dummy_hcd "
                              "and usb_f_fs, or use the loopback transport";
      libusb_exit(context_);
      throw TransportError("libusb: no USB device " + address + " could be opened: " + why);
    }
    libusb_set_auto_detach_kernel_driver(handle_, 1);
    r = libusb_claim_interface(handle_, kBulkInterface);
    if (r != 0) {
      libusb_close(handle_);
      libusb_exit(context_);
      throw TransportError("libusb: cannot claim interface 0 of " + address + ": " + libusb_strerror(r) +
                           " (another program holds it?)");
    }
    find_bulk_endpoints();
    for (auto& slot : in_) {
      slot.transfer = libusb_alloc_transfer(0);
      libusb_fill_bulk_transfer(slot.transfer, handle_, endpoint_in_, slot.buffer, sizeof slot.buffer,
                                &LibusbTransport::on_in, this, 0);
      if (libusb_submit_transfer(slot.transfer) != 0) errors_ |= kDisconnected;
      else ++pending_;
    }
    for (auto& slot : out_) slot.transfer = libusb_alloc_transfer(0);
  }

  ~LibusbTransport() override {
    for (auto& slot : in_) libusb_cancel_transfer(slot.transfer);
    for (auto& slot : out_)
      if (slot.busy) libusb_cancel_transfer(slot.transfer);
    timeval tv{0, 10000};
    for (int i = 0; i < 100 && (pending_ > 0 || busy_out()); ++i)
      libusb_handle_events_timeout_completed(context_, &tv, nullptr);
    for (auto& slot : in_) libusb_free_transfer(slot.transfer);
    for (auto& slot : out_) libusb_free_transfer(slot.transfer);
    libusb_release_interface(handle_, kBulkInterface);
    libusb_close(handle_);
    libusb_exit(context_);
  }

  Io send(const WireFrame& frame) override {
    service();
    for (auto& slot : out_) {
      if (slot.busy) continue;
      std::memcpy(slot.buffer, frame.data, frame.length);
      libusb_fill_bulk_transfer(slot.transfer, handle_, endpoint_out_, slot.buffer, frame.length,
                                &LibusbTransport::on_out, &slot, 100);
      slot.owner = this;
      if (libusb_submit_transfer(slot.transfer) != 0) {
        errors_ |= kDisconnected;
        return Io::error;
      }
      slot.busy = true;
      return Io::ok;
    }
    errors_ |= kTxFailed;  // eight commands in flight: the device stopped reading
    return Io::error;
  }

  Io receive(WireFrame& frame) override {
    service();
    if (head_ == tail_) return (errors_ & kDisconnected) ? Io::error : Io::empty;
    frame = ring_[tail_ % kRing];
    ++tail_;
    return Io::ok;
  }

  void service() override {
    timeval zero{0, 0};
    libusb_handle_events_timeout_completed(context_, &zero, nullptr);
  }
  int poll_fd() const override { return -1; }
  std::uint32_t error_flags() const override { return errors_; }
  void clear_error_flags() override { errors_ = 0; }
  std::string describe() const override { return "USB bulk (libusb) " + address_; }

 private:
  struct InSlot {
    libusb_transfer* transfer = nullptr;
    unsigned char buffer[64];
  };
  struct OutSlot {
    libusb_transfer* transfer = nullptr;
    unsigned char buffer[64];
    bool busy = false;
    LibusbTransport* owner = nullptr;
  };

  // The device's bulk endpoints on interface 0, from its descriptors: a gadget's UDC may assign
  // other addresses than the nominal 0x01/0x81 (FunctionFS on dummy_hcd does).
  void find_bulk_endpoints() {
    libusb_config_descriptor* config = nullptr;
    if (libusb_get_active_config_descriptor(libusb_get_device(handle_), &config) != 0) return;
    for (int a = 0; config->bNumInterfaces > kBulkInterface && a < config->interface[kBulkInterface].num_altsetting; ++a) {
      const libusb_interface_descriptor& alt = config->interface[kBulkInterface].altsetting[a];
      for (int e = 0; e < alt.bNumEndpoints; ++e) {
        const libusb_endpoint_descriptor& ep = alt.endpoint[e];
        if ((ep.bmAttributes & LIBUSB_TRANSFER_TYPE_MASK) != LIBUSB_TRANSFER_TYPE_BULK) continue;
        if (ep.bEndpointAddress & LIBUSB_ENDPOINT_IN) endpoint_in_ = ep.bEndpointAddress;
        else endpoint_out_ = ep.bEndpointAddress;
      }
    }
    libusb_free_config_descriptor(config);
  }

  bool busy_out() const {
    for (const auto& slot : out_)
      if (slot.busy) return true;
    return false;
  }

  static void LIBUSB_CALL on_in(libusb_transfer* transfer) {
    auto* self = static_cast<LibusbTransport*>(transfer->user_data);
    if (transfer->status == LIBUSB_TRANSFER_COMPLETED && transfer->actual_length > 0) {
      if (self->head_ - self->tail_ >= kRing) {
        self->errors_ |= kRxOverflow;
        ++self->tail_;  // keep the newest: the loop wants the latest state
      }
      WireFrame& frame = self->ring_[self->head_ % kRing];
      frame.length = static_cast<std::uint8_t>(transfer->actual_length);
      std::memcpy(frame.data, transfer->buffer, frame.length);
      ++self->head_;
    }
    if (transfer->status == LIBUSB_TRANSFER_NO_DEVICE || transfer->status == LIBUSB_TRANSFER_CANCELLED ||
        libusb_submit_transfer(transfer) != 0) {
      if (transfer->status != LIBUSB_TRANSFER_CANCELLED) self->errors_ |= kDisconnected;
      --self->pending_;
    }
  }

  static void LIBUSB_CALL on_out(libusb_transfer* transfer) {
    auto* slot = static_cast<OutSlot*>(transfer->user_data);
    slot->busy = false;
    if (transfer->status == LIBUSB_TRANSFER_NO_DEVICE) slot->owner->errors_ |= kDisconnected;
    else if (transfer->status != LIBUSB_TRANSFER_COMPLETED && transfer->status != LIBUSB_TRANSFER_CANCELLED)
      slot->owner->errors_ |= kTxFailed;
  }

  std::string address_;
  libusb_context* context_ = nullptr;
  libusb_device_handle* handle_ = nullptr;
  std::array<InSlot, kInTransfers> in_{};
  std::array<OutSlot, kOutTransfers> out_{};
  std::array<WireFrame, kRing> ring_{};
  std::uint64_t head_ = 0, tail_ = 0;
  std::uint8_t endpoint_in_ = kBulkEndpointIn;
  std::uint8_t endpoint_out_ = kBulkEndpointOut;
  int pending_ = 0;
  std::uint32_t errors_ = 0;
};

}  // namespace

std::unique_ptr<Transport> open_libusb_transport(const std::string& address) {
  return std::make_unique<LibusbTransport>(address);
}

}  // namespace hapfluid::device
