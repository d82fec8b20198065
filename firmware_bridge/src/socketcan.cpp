// SocketCAN transport: every syscall checked, every failure named with its fix, and a missing
// interface told apart from a wrong one (open_failure.hpp).
#include "hapfluid/device/socketcan.hpp"

#include <linux/can/raw.h>
#include <net/if.h>
#include <net/if_arp.h>
#include <sys/ioctl.h>
#include <sys/socket.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>

#include "can_wire.hpp"

namespace hapfluid::device {

struct CanSocket {
  int fd = -1;
};

namespace {

void close_socket(CanSocket* s) {
  if (s->fd >= 0) ::close(s->fd);
  delete s;
}

// nullptr with `attempt` filled in (the fd, if any, closed).
CanSocket* refuse(CanSocket* s, OpenAttempt& attempt, OpenFailure failure, const std::string& why) {
  close_socket(s);
  attempt.failure = failure;
  attempt.why = why;
  return nullptr;
}

std::string errno_text(int error) { return std::strerror(error); }

// A CAN_RAW socket bound to `interface` with the node's filter; blocks and allocates (the
// constructor and the reopen worker only).
CanSocket* open_socket(const std::string& interface, bool can_fd, unsigned node, OpenAttempt& attempt) {
  auto* s = new CanSocket;
  s->fd = ::socket(PF_CAN, SOCK_RAW | SOCK_NONBLOCK | SOCK_CLOEXEC, CAN_RAW);
  if (s->fd < 0) {
    // Permanent whatever the errno: a kernel without can-raw, or a unit whose
    // RestrictAddressFamilies lacks AF_CAN, does not change while haptic-rt waits.
    const int error = errno;
    if (error == EAFNOSUPPORT || error == EPROTONOSUPPORT || error == EINVAL)
      return refuse(s, attempt, OpenFailure::permanent,
                    "SocketCAN is not available in this kernel (" + errno_text(error) +
                        "): load can-raw and, for tests, vcan (modprobe can-raw vcan), or use the loopback transport");
    return refuse(s, attempt, OpenFailure::permanent, "SocketCAN: socket(PF_CAN, CAN_RAW): " + errno_text(error));
  }
  ifreq request{};
  std::memcpy(request.ifr_name, interface.c_str(), interface.size() + 1);
  if (::ioctl(s->fd, SIOCGIFINDEX, &request) != 0) {
    const int error = errno;  // ENODEV: no interface of that name (yet)
    return refuse(s, attempt, classify_errno(error),
                  "no CAN interface '" + interface + "' (" + errno_text(error) + "): plug in the CAN adapter or " +
                      "create it (ip link add " + interface + " type vcan; ip link set up " + interface +
                      "), or fix transport.address in the rig file");
  }
  const int index = request.ifr_ifindex;
  // bind(2) says ENODEV both for an interface that is not CAN and for one that just went away;
  // the hardware type tells the rig's mistake (transport.address = "eth0") from the race.
  if (::ioctl(s->fd, SIOCGIFHWADDR, &request) != 0) {
    const int error = errno;
    return refuse(s, attempt, classify_errno(error), "SocketCAN: " + interface + ": " + errno_text(error));
  }
  if (request.ifr_hwaddr.sa_family != ARPHRD_CAN)
    return refuse(s, attempt, OpenFailure::permanent,
                  "SocketCAN: '" + interface + "' is not a CAN interface (hardware type " +
                      std::to_string(request.ifr_hwaddr.sa_family) + "): fix transport.address in the rig file");
  if (can_fd) {
    int on = 1;
    if (::setsockopt(s->fd, SOL_CAN_RAW, CAN_RAW_FD_FRAMES, &on, sizeof on) != 0)
      return refuse(s, attempt, OpenFailure::permanent,
                    "SocketCAN: " + interface + " cannot carry CAN FD frames (" + errno_text(errno) +
                        "): set its MTU to 72 (ip link set " + interface + " mtu 72) or set can_fd = false");
  }
  // Filter: standard ids of this node only (id & 0x60F == node catches 0x0n0..0x1nF), so a bus
  // with many devices wakes this socket only for its own frames.
  can_filter filter{};
  filter.can_id = node;
  filter.can_mask = CAN_EFF_FLAG | CAN_RTR_FLAG | (node ? 0x60Fu : 0u);
  if (::setsockopt(s->fd, SOL_CAN_RAW, CAN_RAW_FILTER, &filter, sizeof filter) != 0)
    return refuse(s, attempt, OpenFailure::permanent, "SocketCAN: setting the receive filter failed: " + errno_text(errno));
  // Our own frames must not come back (the kernel's default, set here because the driver relies
  // on it): every COMMAND this socket hears for our node is then someone else's.
  int off = 0;
  if (::setsockopt(s->fd, SOL_CAN_RAW, CAN_RAW_RECV_OWN_MSGS, &off, sizeof off) != 0)
    return refuse(s, attempt, OpenFailure::permanent, "SocketCAN: disabling own-frame reception failed: " + errno_text(errno));
  can_err_mask_t errors = CAN_ERR_BUSOFF | CAN_ERR_CRTL | CAN_ERR_RESTARTED | CAN_ERR_PROT | CAN_ERR_ACK |
                          CAN_ERR_BUSERROR;
  if (::setsockopt(s->fd, SOL_CAN_RAW, CAN_RAW_ERR_FILTER, &errors, sizeof errors) != 0)
    return refuse(s, attempt, OpenFailure::permanent, "SocketCAN: enabling error frames failed: " + errno_text(errno));
  sockaddr_can address{};
  address.can_family = AF_CAN;
  address.can_ifindex = index;
  // An interface that is down binds (the kernel flags the socket ENETDOWN and it carries frames
  // once the interface is up); ENODEV here is an interface removed since SIOCGIFINDEX.
  if (::bind(s->fd, reinterpret_cast<sockaddr*>(&address), sizeof address) != 0) {
    const int error = errno;
    return refuse(s, attempt, classify_errno(error), "SocketCAN: bind to " + interface + " failed: " + errno_text(error));
  }
  return s;
}

}  // namespace

SocketCanTransport::SocketCanTransport(const std::string& interface, bool can_fd, unsigned node)
    : interface_(interface),
      can_fd_(can_fd),
      node_(node),
      reopen_(describe(), [this](OpenAttempt& a) { return open_socket(interface_, can_fd_, node_, a); }, close_socket) {
  if (interface.empty() || interface.size() >= IFNAMSIZ)
    throw TransportError("SocketCAN: interface name '" + interface + "' is empty or too long");
  OpenAttempt attempt;
  live_ = reopen_.first_open(attempt);
  if (!live_ && attempt.failure == OpenFailure::permanent) throw TransportError(attempt.why);
  if (!live_) errors_ |= kDisconnected;  // a link fault until the interface exists and the worker binds it
}

SocketCanTransport::~SocketCanTransport() {
  if (live_) close_socket(live_);
}  // then reopen_ stops its thread and closes any socket it still holds

int SocketCanTransport::poll_fd() const { return live_ ? live_->fd : -1; }

bool SocketCanTransport::adopt() {
  live_ = reopen_.take();
  if (!live_) return false;
  errors_ &= ~kDisconnected;
  ++reconnects_;
  return true;
}

// ENETDOWN: the interface is down (ip link set down): the socket stays bound and carries frames
// again once it is up. ENODEV / ENXIO: the interface was removed (a USB-CAN adapter unplugged)
// and the kernel unbound the socket: it is handed to the worker, which binds a new one once an
// interface of that name is back. Anything else (ENOBUFS: tx queue full at bus-off or without
// an ack) sets `otherwise`: the next tick sends a fresh frame.
void SocketCanTransport::failed(int error, std::uint32_t otherwise) {
  if (error == ENETDOWN) {
    errors_ |= kDisconnected;
  } else if (classify_errno(error) == OpenFailure::absent) {
    errors_ |= kDisconnected;
    reopen_.retire(live_);
    live_ = nullptr;
  } else {
    errors_ |= otherwise;
  }
}

Io SocketCanTransport::send(const WireFrame& frame) {
  if (!live_ && !adopt()) return Io::error;  // no interface: kDisconnected is set
  canfd_frame kernel;
  to_kernel(frame, kernel);
  std::size_t size = frame.fd ? CANFD_MTU : CAN_MTU;
  ssize_t n = ::write(live_->fd, &kernel, size);
  if (n == static_cast<ssize_t>(size)) return Io::ok;
  failed(errno, kTxFailed);
  return Io::error;
}

Io SocketCanTransport::receive(WireFrame& frame) {
  if (!live_ && !adopt()) return Io::error;
  for (;;) {
    canfd_frame kernel;
    ssize_t n = ::read(live_->fd, &kernel, sizeof kernel);
    if (n < 0) {
      if (errno == EAGAIN || errno == EWOULDBLOCK) return Io::empty;
      failed(errno, 0);
      return Io::error;
    }
    if (n != CAN_MTU && n != CANFD_MTU) continue;
    if (kernel.can_id & CAN_ERR_FLAG) {
      can_frame error;
      std::memcpy(&error, &kernel, sizeof error);
      errors_ = can_error_bits(error, errors_);
      continue;
    }
    errors_ &= ~kDisconnected;
    from_kernel(kernel, n == CANFD_MTU, frame);
    return Io::ok;
  }
}

}  // namespace hapfluid::device
