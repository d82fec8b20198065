// FunctionFS device side (see functionfs_transport.hpp).
#include "functionfs_transport.hpp"

#include <fcntl.h>
#include <linux/usb/ch9.h>
#include <linux/usb/functionfs.h>
#include <poll.h>
#include <sys/eventfd.h>
#include <unistd.h>

#include <atomic>
#include <cerrno>
#include <condition_variable>
#include <cstring>
#include <deque>
#include <mutex>
#include <thread>

namespace hapfluid::fake {

struct FunctionFsTransport::Shared {
  int ep0 = -1, ep_in = -1, ep_out = -1, event_fd = -1;
  std::mutex mutex;
  std::condition_variable tx_ready;
  std::deque<device::WireFrame> rx, tx;
  std::atomic<std::uint32_t> errors{device::kDisconnected};  // until the host enables the function
  std::atomic<bool> stop{false};
  std::thread reader, writer;
};

namespace {

// Full-speed and high-speed descriptor sets: one vendor interface, bulk IN (ep1) and OUT (ep2).
struct __attribute__((packed)) Descriptors {
  usb_functionfs_descs_head_v2 header;
  __le32 fs_count, hs_count;
  struct __attribute__((packed)) Set {
    usb_interface_descriptor interface;
    usb_endpoint_descriptor_no_audio in, out;
  } fs, hs;
};

struct __attribute__((packed)) Strings {
  usb_functionfs_strings_head header;
  __le16 language;
  char interface_name[sizeof "hapfluid haptic arm"];
};

Descriptors::Set descriptor_set(std::uint16_t max_packet) {
  Descriptors::Set s{};
  s.interface = {USB_DT_INTERFACE_SIZE, USB_DT_INTERFACE, 0, 0, 2, USB_CLASS_VENDOR_SPEC, 0, 0, 1};
  s.in = {USB_DT_ENDPOINT_SIZE, USB_DT_ENDPOINT, 1 | USB_DIR_IN, USB_ENDPOINT_XFER_BULK, max_packet, 0};
  s.out = {USB_DT_ENDPOINT_SIZE, USB_DT_ENDPOINT, 2 | USB_DIR_OUT, USB_ENDPOINT_XFER_BULK, max_packet, 0};
  return s;
}

void reader_loop(std::shared_ptr<FunctionFsTransport::Shared> s) {
  while (!s->stop) {
    device::WireFrame frame;
    ssize_t n = ::read(s->ep_out, frame.data, sizeof frame.data);
    if (n > 0) {
      frame.length = static_cast<std::uint8_t>(n);
      std::lock_guard<std::mutex> lock(s->mutex);
      if (s->rx.size() < 256) s->rx.push_back(frame);
      else s->errors |= device::kRxOverflow;
      std::uint64_t one = 1;
      (void)!::write(s->event_fd, &one, sizeof one);
    } else if (n < 0 && !s->stop) {
      s->errors |= device::kDisconnected;  // ESHUTDOWN: not enabled by the host (yet)
      ::usleep(5000);
    }
  }
}

void writer_loop(std::shared_ptr<FunctionFsTransport::Shared> s) {
  std::unique_lock<std::mutex> lock(s->mutex);
  while (!s->stop) {
    s->tx_ready.wait(lock, [&] { return s->stop || !s->tx.empty(); });
    if (s->stop) break;
    device::WireFrame frame = s->tx.front();
    s->tx.pop_front();
    lock.unlock();
    if (::write(s->ep_in, frame.data, frame.length) != frame.length) s->errors |= device::kTxFailed;
    lock.lock();
  }
}

}  // namespace

FunctionFsTransport::FunctionFsTransport(const std::string& mount_dir)
    : mount_dir_(mount_dir), shared_(std::make_shared<Shared>()) {
  Shared& s = *shared_;
  s.ep0 = ::open((mount_dir + "/ep0").c_str(), O_RDWR | O_CLOEXEC);
  if (s.ep0 < 0)
    throw device::TransportError(
        "FunctionFS: no " + mount_dir + "/ep0 (" + std::strerror(errno) +
        "): the kernel needs usb_f_fs, libcomposite and a UDC (dummy_hcd for tests), and a configfs gadget with "
        "an ffs function mounted there (mount -t functionfs NAME " + mount_dir + ")");
  Descriptors d{};
  d.header.magic = FUNCTIONFS_DESCRIPTORS_MAGIC_V2;
  d.header.length = sizeof d;
  d.header.flags = FUNCTIONFS_HAS_FS_DESC | FUNCTIONFS_HAS_HS_DESC;
  d.fs_count = 3;
  d.hs_count = 3;
  d.fs = descriptor_set(64);
  d.hs = descriptor_set(512);
  Strings str{};
  str.header.magic = FUNCTIONFS_STRINGS_MAGIC;
  str.header.length = sizeof str;
  str.header.str_count = 1;
  str.header.lang_count = 1;
  str.language = 0x0409;
  std::memcpy(str.interface_name, "hapfluid haptic arm", sizeof str.interface_name);
  if (::write(s.ep0, &d, sizeof d) != static_cast<ssize_t>(sizeof d) ||
      ::write(s.ep0, &str, sizeof str) != static_cast<ssize_t>(sizeof str)) {
    int error = errno;
    ::close(s.ep0);
    throw device::TransportError("FunctionFS: writing descriptors to " + mount_dir + "/ep0 failed: " +
                                 std::strerror(error));
  }
  s.ep_in = ::open((mount_dir + "/ep1").c_str(), O_RDWR | O_CLOEXEC);
  s.ep_out = ::open((mount_dir + "/ep2").c_str(), O_RDWR | O_CLOEXEC);
  s.event_fd = ::eventfd(0, EFD_NONBLOCK | EFD_CLOEXEC);
  if (s.ep_in < 0 || s.ep_out < 0 || s.event_fd < 0) {
    int error = errno;
    ::close(s.ep0);
    throw device::TransportError("FunctionFS: opening the endpoints in " + mount_dir + " failed: " +
                                 std::strerror(error));
  }
  int flags = ::fcntl(s.ep0, F_GETFL);
  ::fcntl(s.ep0, F_SETFL, flags | O_NONBLOCK);  // events are polled from receive()
  s.reader = std::thread(reader_loop, shared_);
  s.writer = std::thread(writer_loop, shared_);
}

FunctionFsTransport::~FunctionFsTransport() {
  Shared& s = *shared_;
  s.stop = true;
  s.tx_ready.notify_all();
  ::close(s.ep0);  // the function goes away: blocked endpoint I/O returns and the threads end
  ::close(s.ep_in);
  ::close(s.ep_out);
  s.reader.detach();  // they hold the shared state; a read that never returns cannot hang the exit
  if (s.writer.joinable()) s.writer.join();
}

void FunctionFsTransport::service_ep0() {
  Shared& s = *shared_;
  usb_functionfs_event events[4];
  for (;;) {
    ssize_t n = ::read(s.ep0, events, sizeof events);
    if (n <= 0) return;
    for (std::size_t i = 0; i < static_cast<std::size_t>(n) / sizeof events[0]; ++i) {
      switch (events[i].type) {
        case FUNCTIONFS_ENABLE: s.errors &= ~device::kDisconnected; break;
        case FUNCTIONFS_DISABLE:
        case FUNCTIONFS_UNBIND: s.errors |= device::kDisconnected; break;
        case FUNCTIONFS_SETUP:  // no vendor requests: stall by doing I/O in the wrong direction
          if (events[i].u.setup.bRequestType & USB_DIR_IN) (void)!::read(s.ep0, nullptr, 0);
          else (void)!::write(s.ep0, nullptr, 0);
          break;
        default: break;
      }
    }
  }
}

device::Io FunctionFsTransport::send(const device::WireFrame& frame) {
  Shared& s = *shared_;
  std::lock_guard<std::mutex> lock(s.mutex);
  if (s.tx.size() >= 64) {
    s.errors |= device::kTxFailed;  // the host stopped reading: drop, like a full IN FIFO
    return device::Io::error;
  }
  s.tx.push_back(frame);
  s.tx_ready.notify_one();
  return device::Io::ok;
}

device::Io FunctionFsTransport::receive(device::WireFrame& frame) {
  service_ep0();
  Shared& s = *shared_;
  std::uint64_t count;
  (void)!::read(s.event_fd, &count, sizeof count);
  std::lock_guard<std::mutex> lock(s.mutex);
  if (s.rx.empty()) return device::Io::empty;
  frame = s.rx.front();
  s.rx.pop_front();
  return device::Io::ok;
}

int FunctionFsTransport::poll_fd() const { return shared_->event_fd; }
std::uint32_t FunctionFsTransport::error_flags() const { return shared_->errors; }
void FunctionFsTransport::clear_error_flags() { shared_->errors = 0; }

}  // namespace hapfluid::fake
