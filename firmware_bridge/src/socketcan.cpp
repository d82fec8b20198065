// SocketCAN transport: every syscall checked, every failure named with its fix.
#include "hapfluid/device/socketcan.hpp"

#include <linux/can/raw.h>
#include <net/if.h>
#include <sys/ioctl.h>
#include <sys/socket.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>

#include "can_wire.hpp"

namespace hapfluid::device {

namespace {

[[noreturn]] void fail(int fd, const std::string& what) {
  if (fd >= 0) ::close(fd);
  throw TransportError(what);
}

}  // namespace

SocketCanTransport::SocketCanTransport(const std::string& interface, bool can_fd, unsigned node)
    : interface_(interface), can_fd_(can_fd) {
  if (interface.empty() || interface.size() >= IFNAMSIZ)
    throw TransportError("SocketCAN: interface name '" + interface + "' is empty or too long");
  fd_ = ::socket(PF_CAN, SOCK_RAW | SOCK_NONBLOCK | SOCK_CLOEXEC, CAN_RAW);
  if (fd_ < 0) {
    int error = errno;
    if (error == EAFNOSUPPORT || error == EPROTONOSUPPORT || error == EINVAL)
      fail(-1, "SocketCAN is not available in this kernel (" + std::string(std::strerror(error)) +
                   "): load can-raw and, for tests, vcan (modprobe can-raw vcan), or use the loopback transport");
    fail(-1, "SocketCAN: socket(PF_CAN, CAN_RAW): " + std::string(std::strerror(error)));
  }
  ifreq request{};
  std::memcpy(request.ifr_name, interface.c_str(), interface.size() + 1);
  if (::ioctl(fd_, SIOCGIFINDEX, &request) != 0)
    fail(fd_, "SocketCAN: no CAN interface '" + interface + "' (" + std::strerror(errno) +
                  "): create it (ip link add " + interface + " type vcan; ip link set up " + interface +
                  ") or fix transport.address in the rig file");
  if (can_fd) {
    int on = 1;
    if (::setsockopt(fd_, SOL_CAN_RAW, CAN_RAW_FD_FRAMES, &on, sizeof on) != 0)
      fail(fd_, "SocketCAN: " + interface + " cannot carry CAN FD frames (" + std::strerror(errno) +
                    "): set its MTU to 72 (ip link set " + interface + " mtu 72) or set can_fd = false");
  }
  // Filter: standard ids of this node only (id & 0x60F == node catches 0x0n0..0x1nF), so a bus
  // with many devices wakes this socket only for its own frames.
  can_filter filter{};
  filter.can_id = node;
  filter.can_mask = CAN_EFF_FLAG | CAN_RTR_FLAG | (node ? 0x60Fu : 0u);
  if (::setsockopt(fd_, SOL_CAN_RAW, CAN_RAW_FILTER, &filter, sizeof filter) != 0)
    fail(fd_, "SocketCAN: setting the receive filter failed: " + std::string(std::strerror(errno)));
  can_err_mask_t errors = CAN_ERR_BUSOFF | CAN_ERR_CRTL | CAN_ERR_RESTARTED | CAN_ERR_PROT | CAN_ERR_ACK |
                          CAN_ERR_BUSERROR;
  if (::setsockopt(fd_, SOL_CAN_RAW, CAN_RAW_ERR_FILTER, &errors, sizeof errors) != 0)
    fail(fd_, "SocketCAN: enabling error frames failed: " + std::string(std::strerror(errno)));
  sockaddr_can address{};
  address.can_family = AF_CAN;
  address.can_ifindex = request.ifr_ifindex;
  if (::bind(fd_, reinterpret_cast<sockaddr*>(&address), sizeof address) != 0)
    fail(fd_, "SocketCAN: bind to " + interface + " failed: " + std::strerror(errno));
}

SocketCanTransport::~SocketCanTransport() {
  if (fd_ >= 0) ::close(fd_);
}

Io SocketCanTransport::send(const WireFrame& frame) {
  canfd_frame kernel;
  to_kernel(frame, kernel);
  std::size_t size = frame.fd ? CANFD_MTU : CAN_MTU;
  ssize_t n = ::write(fd_, &kernel, size);
  if (n == static_cast<ssize_t>(size)) return Io::ok;
  // ENOBUFS: the tx queue is full (bus-off, no ack): drop the frame, the next tick sends a fresh one
  if (errno == ENETDOWN) errors_ |= kDisconnected;
  else errors_ |= kTxFailed;
  return Io::error;
}

Io SocketCanTransport::receive(WireFrame& frame) {
  for (;;) {
    canfd_frame kernel;
    ssize_t n = ::read(fd_, &kernel, sizeof kernel);
    if (n < 0) {
      if (errno == EAGAIN || errno == EWOULDBLOCK) return Io::empty;
      if (errno == ENETDOWN) errors_ |= kDisconnected;
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
