// Loopback transport (see loopback.hpp): the bus end relays, the peer end talks to the bus.
#include "hapfluid/device/loopback.hpp"

#include <fcntl.h>
#include <sys/socket.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>

#include "can_wire.hpp"

namespace hapfluid::device {

namespace {

std::string errno_text(int error) { return std::strerror(error); }

bool refused(int error) { return error == ECONNREFUSED || error == ENOENT || error == ENOTCONN; }

}  // namespace

LoopbackTransport::LoopbackTransport(const std::string& path, LoopbackRole role, LoopbackFormat format)
    : path_(path), role_(role), format_(format) {
  if (path.empty() || path.size() >= sizeof(bus_address_.sun_path))
    throw TransportError("loopback: socket path '" + path + "' is empty or longer than " +
                         std::to_string(sizeof(bus_address_.sun_path) - 1) + " bytes");
  bus_address_.sun_family = AF_UNIX;
  std::memcpy(bus_address_.sun_path, path.c_str(), path.size() + 1);
  bus_length_ = static_cast<socklen_t>(offsetof(sockaddr_un, sun_path) + path.size() + 1);
  fd_ = ::socket(AF_UNIX, SOCK_DGRAM | SOCK_NONBLOCK | SOCK_CLOEXEC, 0);
  if (fd_ < 0) throw TransportError("loopback: socket(AF_UNIX): " + errno_text(errno));
  int buffer = 1 << 20;  // a few hundred ms of 1 kHz traffic, so a slow reader drops nothing
  ::setsockopt(fd_, SOL_SOCKET, SO_RCVBUF, &buffer, sizeof buffer);
  ::setsockopt(fd_, SOL_SOCKET, SO_SNDBUF, &buffer, sizeof buffer);
  if (role == LoopbackRole::bus) {
    struct stat st {};
    if (::lstat(path.c_str(), &st) == 0 && S_ISSOCK(st.st_mode)) ::unlink(path.c_str());
    if (::bind(fd_, reinterpret_cast<const sockaddr*>(&bus_address_), bus_length_) != 0) {
      int error = errno;
      ::close(fd_);
      throw TransportError("loopback: cannot bind bus socket '" + path + "': " + errno_text(error));
    }
    return;
  }
  sa_family_t family = AF_UNIX;  // autobind: a unique abstract address, nothing to clean up
  if (::bind(fd_, reinterpret_cast<const sockaddr*>(&family), sizeof family) != 0) {
    int error = errno;
    ::close(fd_);
    throw TransportError("loopback: autobind failed: " + errno_text(error));
  }
  if (::sendto(fd_, nullptr, 0, 0, reinterpret_cast<const sockaddr*>(&bus_address_), bus_length_) != 0) {
    int error = errno;
    ::close(fd_);
    throw TransportError("loopback: no bus at '" + path + "' (" + errno_text(error) +
                         "): start haptic-fake-device --transport loopback --address " + path + " first");
  }
}

LoopbackTransport::~LoopbackTransport() {
  if (fd_ >= 0) ::close(fd_);
  if (role_ == LoopbackRole::bus) ::unlink(path_.c_str());
}

std::string LoopbackTransport::describe() const {
  return std::string("loopback ") + (role_ == LoopbackRole::bus ? "bus " : "peer of ") + path_;
}

void LoopbackTransport::add_peer(const sockaddr_un& address, socklen_t length) {
  for (int i = 0; i < peers_; ++i)
    if (peer_length_[i] == length && std::memcmp(&peer_address_[i], &address, length) == 0) return;
  if (peers_ == kMaxPeers) return;  // a full bus ignores newcomers rather than evict the host
  peer_address_[peers_] = address;
  peer_length_[peers_] = length;
  ++peers_;
}

void LoopbackTransport::drop_peer(int index) {
  peer_address_[index] = peer_address_[peers_ - 1];
  peer_length_[index] = peer_length_[peers_ - 1];
  --peers_;
}

bool LoopbackTransport::send_bytes(const void* bytes, std::size_t length, const sockaddr_un& to,
                                   socklen_t to_length) {
  ssize_t n = ::sendto(fd_, bytes, length, MSG_DONTWAIT, reinterpret_cast<const sockaddr*>(&to), to_length);
  return n == static_cast<ssize_t>(length);
}

void LoopbackTransport::relay(const std::uint8_t* bytes, std::size_t length, const sockaddr_un& from,
                              socklen_t from_length) {
  for (int i = peers_ - 1; i >= 0; --i) {
    if (peer_length_[i] == from_length && std::memcmp(&peer_address_[i], &from, from_length) == 0) continue;
    if (!send_bytes(bytes, length, peer_address_[i], peer_length_[i]) && refused(errno)) drop_peer(i);
  }
}

Io LoopbackTransport::send(const WireFrame& frame) {
  std::uint8_t bytes[sizeof(canfd_frame)];
  std::size_t length = frame.length;
  if (format_ == LoopbackFormat::can) {
    canfd_frame kernel;
    to_kernel(frame, kernel);
    length = frame.fd ? sizeof(canfd_frame) : sizeof(can_frame);  // CAN_MTU or CANFD_MTU, as on SocketCAN
    std::memcpy(bytes, &kernel, length);
  } else {
    std::memcpy(bytes, frame.data, length);
  }
  if (role_ == LoopbackRole::peer) {
    if (send_bytes(bytes, length, bus_address_, bus_length_)) {
      errors_ &= ~kDisconnected;
      return Io::ok;
    }
    errors_ |= refused(errno) ? kDisconnected : kTxFailed;
    return Io::error;
  }
  for (int i = peers_ - 1; i >= 0; --i) {
    if (send_bytes(bytes, length, peer_address_[i], peer_length_[i])) continue;
    if (refused(errno)) drop_peer(i);
    else errors_ |= kTxFailed;  // a peer that does not read: its frames are lost, not ours
  }
  return Io::ok;
}

Io LoopbackTransport::receive(WireFrame& frame) {
  for (;;) {
    std::uint8_t bytes[sizeof(canfd_frame) + 8];
    sockaddr_un from{};
    socklen_t from_length = sizeof from;
    ssize_t n = ::recvfrom(fd_, bytes, sizeof bytes, MSG_DONTWAIT, reinterpret_cast<sockaddr*>(&from),
                           &from_length);
    if (n < 0) return (errno == EAGAIN || errno == EWOULDBLOCK) ? Io::empty : Io::error;
    if (role_ == LoopbackRole::bus) {
      add_peer(from, from_length);
      if (n == 0) continue;  // registration only
      relay(bytes, static_cast<std::size_t>(n), from, from_length);
    }
    if (n == 0) continue;
    if (format_ == LoopbackFormat::can) {
      if (n != sizeof(can_frame) && n != sizeof(canfd_frame)) continue;  // not a CAN frame: not on a CAN bus
      canfd_frame kernel{};
      std::memcpy(&kernel, bytes, static_cast<std::size_t>(n));
      if (kernel.can_id & CAN_ERR_FLAG) {
        can_frame error{};
        std::memcpy(&error, bytes, sizeof error);
        errors_ = can_error_bits(error, errors_);
        continue;
      }
      from_kernel(kernel, n == sizeof(canfd_frame), frame);
      return Io::ok;
    }
    if (n > 64) continue;
    frame.can_id = 0;
    frame.fd = false;
    frame.length = static_cast<std::uint8_t>(n);
    std::memcpy(frame.data, bytes, static_cast<std::size_t>(n));
    return Io::ok;
  }
}

}  // namespace hapfluid::device
