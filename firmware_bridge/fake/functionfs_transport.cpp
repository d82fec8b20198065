// FunctionFS device side (see functionfs_transport.hpp).
#include "functionfs_transport.hpp"

#include <fcntl.h>
#include <linux/usb/ch9.h>
#include <linux/usb/functionfs.h>
#include <poll.h>
#include <pthread.h>
#include <signal.h>
#include <sys/eventfd.h>
#include <time.h>
#include <unistd.h>

#include <atomic>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <condition_variable>
#include <cstring>
#include <deque>
#include <mutex>
#include <thread>

#include "hapfluid/config/log.hpp"

namespace hapfluid::fake {

struct FunctionFsTransport::Shared {
  int ep0 = -1, ep_in = -1, ep_out = -1, event_fd = -1;
  long out_interval_ns = 0;
  std::mutex mutex;
  std::condition_variable tx_ready;
  std::deque<device::WireFrame> rx, tx;
  std::atomic<std::uint32_t> errors{device::kDisconnected};  // until the host enables the function
  std::atomic<bool> stop{false};
  std::atomic<bool> reader_done{false}, writer_done{false};
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

// Shutdown. FunctionFS endpoint files have no poll() and no non-blocking transfers (O_NONBLOCK
// only refuses to wait for the host to enable the function): a write on ep_in blocks until the
// host reads, a read on ep_out until it writes, and close() from another thread does not end a
// call in progress. Both waits are interruptible, though (f_fs.c ffs_epfile_io: an interrupted
// transfer is dequeued and the call returns EINTR), so the destructor sends this signal to the
// I/O threads; its handler does nothing and is installed without SA_RESTART.
constexpr int kWakeSignal = SIGUSR2;

void on_wake_signal(int) {}

void install_wake_signal() {
  static const bool installed = [] {
    struct sigaction sa {};
    sa.sa_handler = on_wake_signal;
    sigemptyset(&sa.sa_mask);
    sa.sa_flags = 0;  // no SA_RESTART: the blocked endpoint call must return EINTR
    return sigaction(kWakeSignal, &sa, nullptr) == 0;
  }();
  if (!installed) throw device::TransportError("FunctionFS: cannot install the shutdown signal handler");
}

// The I/O threads take only the wake signal: the program's SIGINT/SIGTERM go to its main thread.
void block_process_signals() {
  sigset_t set;
  sigemptyset(&set);
  sigaddset(&set, SIGINT);
  sigaddset(&set, SIGTERM);
  pthread_sigmask(SIG_BLOCK, &set, nullptr);
}

void reader_loop(std::shared_ptr<FunctionFsTransport::Shared> s) {
  block_process_signals();
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
    } else if (n < 0 && errno != EINTR && !s->stop) {
      s->errors |= device::kDisconnected;  // ESHUTDOWN: not enabled by the host (yet)
      ::usleep(5000);
    }
    if (n > 0 && s->out_interval_ns > 0) {  // a slow device; the wake signal ends the nap early
      timespec nap{s->out_interval_ns / 1'000'000'000, s->out_interval_ns % 1'000'000'000};
      nanosleep(&nap, nullptr);
    }
  }
  s->reader_done = true;
}

void writer_loop(std::shared_ptr<FunctionFsTransport::Shared> s) {
  block_process_signals();
  std::unique_lock<std::mutex> lock(s->mutex);
  while (!s->stop) {
    s->tx_ready.wait(lock, [&] { return s->stop || !s->tx.empty(); });
    if (s->stop) break;
    device::WireFrame frame = s->tx.front();
    s->tx.pop_front();
    lock.unlock();
    // Blocks while the host does not read. EINTR is the destructor's wake-up (or, before stop,
    // a stray signal: the packet is dropped like any that an IN FIFO could not take).
    if (::write(s->ep_in, frame.data, frame.length) != frame.length && !s->stop) s->errors |= device::kTxFailed;
    lock.lock();
  }
  s->writer_done = true;
}

// Wakes `thread` with the wake signal until it reports `done` (a signal sent just before the
// thread enters its blocking call is not seen by that call, hence the repeats), then joins it.
// False if it did not end within `limit_ms`; it is then left detached.
bool stop_thread(std::thread& thread, const std::atomic<bool>& done, int limit_ms) {
  if (!thread.joinable()) return true;
  for (int waited_ms = 0; !done; waited_ms += 5) {
    if (waited_ms >= limit_ms) {
      thread.detach();
      return false;
    }
    if (waited_ms % 20 == 0) pthread_kill(thread.native_handle(), kWakeSignal);
    timespec nap{0, 5'000'000};
    nanosleep(&nap, nullptr);
  }
  thread.join();
  return true;
}

}  // namespace

FunctionFsTransport::FunctionFsTransport(const std::string& mount_dir, double out_interval_ms)
    : mount_dir_(mount_dir), shared_(std::make_shared<Shared>()) {
  Shared& s = *shared_;
  s.out_interval_ns = std::lround(out_interval_ms * 1e6);
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
  install_wake_signal();
  s.reader = std::thread(reader_loop, shared_);
  s.writer = std::thread(writer_loop, shared_);
}

FunctionFsTransport::~FunctionFsTransport() {
  Shared& s = *shared_;
  {
    std::lock_guard<std::mutex> lock(s.mutex);
    s.stop = true;
  }
  s.tx_ready.notify_all();
  // Bounded: each thread is either waiting on the queue (woken above) or blocked in endpoint
  // I/O that the wake signal interrupts, so this takes milliseconds, also when the host stopped
  // reading long ago (the case that used to hang SIGTERM).
  const bool writer_ended = stop_thread(s.writer, s.writer_done, 2000);
  const bool reader_ended = stop_thread(s.reader, s.reader_done, 2000);
  if (!writer_ended || !reader_ended)
    log::warning("FunctionFS %s: an endpoint thread did not end within 2 s; left detached",
                 mount_dir_.c_str());
  ::close(s.ep_in);
  ::close(s.ep_out);
  ::close(s.ep0);  // last: the function goes away once every endpoint file is closed
  ::close(s.event_fd);
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
