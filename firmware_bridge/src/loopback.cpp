// Loopback transport (see loopback.hpp): the bus end accepts and relays, the peer end connects.
#include "hapfluid/device/loopback.hpp"

#include <sys/epoll.h>
#include <sys/socket.h>
#include <sys/stat.h>
#include <sys/un.h>
#include <time.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>

#include "can_wire.hpp"

namespace hapfluid::device {

namespace {

std::string errno_text(int error) { return std::strerror(error); }

bool gone(int error) { return error == EPIPE || error == ECONNRESET || error == ENOTCONN || error == ECONNREFUSED; }

std::uint64_t now_ns() {
  timespec ts;
  clock_gettime(CLOCK_MONOTONIC, &ts);
  return static_cast<std::uint64_t>(ts.tv_sec) * 1'000'000'000ull + static_cast<std::uint64_t>(ts.tv_nsec);
}

int make_socket() {
  int fd = ::socket(AF_UNIX, SOCK_SEQPACKET | SOCK_NONBLOCK | SOCK_CLOEXEC, 0);
  if (fd < 0) return -1;
  int buffer = 1 << 20;  // hundreds of ms of 1 kHz traffic, so a briefly starved reader drops nothing
  ::setsockopt(fd, SOL_SOCKET, SO_SNDBUF, &buffer, sizeof buffer);
  ::setsockopt(fd, SOL_SOCKET, SO_RCVBUF, &buffer, sizeof buffer);
  return fd;
}

sockaddr_un address_of(const std::string& path, socklen_t& length) {
  sockaddr_un a{};
  a.sun_family = AF_UNIX;
  std::memcpy(a.sun_path, path.c_str(), path.size() + 1);
  length = static_cast<socklen_t>(offsetof(sockaddr_un, sun_path) + path.size() + 1);
  return a;
}

}  // namespace

LoopbackTransport::LoopbackTransport(const std::string& path, LoopbackRole role, LoopbackFormat format)
    : path_(path), role_(role), format_(format) {
  if (path.empty() || path.size() >= sizeof(sockaddr_un::sun_path))
    throw TransportError("loopback: socket path '" + path + "' is empty or longer than " +
                         std::to_string(sizeof(sockaddr_un::sun_path) - 1) + " bytes");
  socklen_t length = 0;
  const sockaddr_un address = address_of(path, length);
  fd_ = make_socket();
  if (fd_ < 0) throw TransportError("loopback: socket(AF_UNIX, SOCK_SEQPACKET): " + errno_text(errno));
  if (role == LoopbackRole::bus) {
    struct stat st {};
    if (::lstat(path.c_str(), &st) == 0 && S_ISSOCK(st.st_mode)) ::unlink(path.c_str());
    if (::bind(fd_, reinterpret_cast<const sockaddr*>(&address), length) != 0 || ::listen(fd_, kMaxPeers) != 0) {
      int error = errno;
      ::close(fd_);
      throw TransportError("loopback: cannot listen on '" + path + "': " + errno_text(error));
    }
    epoll_fd_ = ::epoll_create1(EPOLL_CLOEXEC);
    epoll_event ev{};
    ev.events = EPOLLIN;
    ev.data.fd = fd_;
    ::epoll_ctl(epoll_fd_, EPOLL_CTL_ADD, fd_, &ev);
    return;
  }
  if (::connect(fd_, reinterpret_cast<const sockaddr*>(&address), length) != 0) {
    int error = errno;
    ::close(fd_);
    fd_ = -1;
    if (error != ENOENT && error != ECONNREFUSED)
      throw TransportError("loopback: cannot connect to the bus at '" + path + "' (" + errno_text(error) + ")");
    // No bus yet (the device process starts later): the same state as a bus that went away, so the
    // host sees a disconnected link and connects by itself once the bus appears.
    errors_ |= kDisconnected;
  }
}

LoopbackTransport::~LoopbackTransport() {
  for (int i = 0; i < peers_; ++i) ::close(peer_fd_[i]);
  if (fd_ >= 0) ::close(fd_);
  if (epoll_fd_ >= 0) ::close(epoll_fd_);
  if (role_ == LoopbackRole::bus) ::unlink(path_.c_str());
}

std::string LoopbackTransport::describe() const {
  return std::string("loopback ") + (role_ == LoopbackRole::bus ? "bus " : "peer of ") + path_;
}

void LoopbackTransport::accept_peers() {
  for (;;) {
    int peer = ::accept4(fd_, nullptr, nullptr, SOCK_NONBLOCK | SOCK_CLOEXEC);
    if (peer < 0) return;
    if (peers_ == kMaxPeers) {  // a full bus turns newcomers away rather than evict the host
      ::close(peer);
      continue;
    }
    int buffer = 1 << 20;
    ::setsockopt(peer, SOL_SOCKET, SO_SNDBUF, &buffer, sizeof buffer);
    epoll_event ev{};
    ev.events = EPOLLIN;
    ev.data.fd = peer;
    ::epoll_ctl(epoll_fd_, EPOLL_CTL_ADD, peer, &ev);
    peer_fd_[peers_++] = peer;
  }
}

void LoopbackTransport::drop_peer(int index) {
  ::epoll_ctl(epoll_fd_, EPOLL_CTL_DEL, peer_fd_[index], nullptr);
  ::close(peer_fd_[index]);
  peer_fd_[index] = peer_fd_[--peers_];
}

bool LoopbackTransport::reconnect() {
  const std::uint64_t now = now_ns();
  if (now < next_reconnect_ns_) return false;
  next_reconnect_ns_ = now + 100'000'000;
  int fd = make_socket();
  if (fd < 0) return false;
  socklen_t length = 0;
  const sockaddr_un address = address_of(path_, length);
  if (::connect(fd, reinterpret_cast<const sockaddr*>(&address), length) != 0) {
    ::close(fd);
    return false;
  }
  if (fd_ >= 0) ::close(fd_);
  fd_ = fd;
  errors_ &= ~kDisconnected;
  ++reconnects_;
  return true;
}

std::size_t LoopbackTransport::encode(const WireFrame& frame, std::uint8_t* bytes) const {
  if (format_ != LoopbackFormat::can) {
    std::memcpy(bytes, frame.data, frame.length);
    return frame.length;
  }
  canfd_frame kernel;
  to_kernel(frame, kernel);
  const std::size_t length = frame.fd ? sizeof(canfd_frame) : sizeof(can_frame);  // CANFD_MTU or CAN_MTU
  std::memcpy(bytes, &kernel, length);
  return length;
}

// False for units that carry no data for the caller (CAN error frames update errors_).
bool LoopbackTransport::decode(const std::uint8_t* bytes, std::size_t n, WireFrame& frame) {
  if (format_ != LoopbackFormat::can) {
    if (n == 0 || n > sizeof frame.data) return false;
    frame.can_id = 0;
    frame.fd = false;
    frame.length = static_cast<std::uint8_t>(n);
    std::memcpy(frame.data, bytes, n);
    return true;
  }
  if (n != sizeof(can_frame) && n != sizeof(canfd_frame)) return false;  // not a CAN frame
  canfd_frame kernel{};
  std::memcpy(&kernel, bytes, n);
  if (kernel.can_id & CAN_ERR_FLAG) {
    can_frame error{};
    std::memcpy(&error, bytes, sizeof error);
    errors_ = can_error_bits(error, errors_);
    return false;
  }
  from_kernel(kernel, n == sizeof(canfd_frame), frame);
  return true;
}

Io LoopbackTransport::send(const WireFrame& frame) {
  std::uint8_t bytes[sizeof(canfd_frame)];
  const std::size_t length = encode(frame, bytes);
  if (role_ == LoopbackRole::peer) {
    if ((errors_ & kDisconnected) && !reconnect()) return Io::error;
    if (::send(fd_, bytes, length, MSG_DONTWAIT | MSG_NOSIGNAL) == static_cast<ssize_t>(length)) return Io::ok;
    errors_ |= gone(errno) ? kDisconnected : kTxFailed;
    return Io::error;
  }
  accept_peers();
  for (int i = peers_ - 1; i >= 0; --i) {
    if (::send(peer_fd_[i], bytes, length, MSG_DONTWAIT | MSG_NOSIGNAL) == static_cast<ssize_t>(length)) continue;
    if (gone(errno)) drop_peer(i);
    else errors_ |= kTxFailed;  // a peer that does not read: its frames are lost, not ours
  }
  return Io::ok;
}

Io LoopbackTransport::receive(WireFrame& frame) {
  std::uint8_t bytes[sizeof(canfd_frame) + 8];
  if (role_ == LoopbackRole::peer) {
    for (;;) {
      if ((errors_ & kDisconnected) && !reconnect()) return Io::error;
      ssize_t n = ::recv(fd_, bytes, sizeof bytes, MSG_DONTWAIT);
      if (n < 0 && (errno == EAGAIN || errno == EWOULDBLOCK)) return Io::empty;
      if (n <= 0) {  // 0: the bus closed the connection
        errors_ |= kDisconnected;
        return Io::error;
      }
      if (decode(bytes, static_cast<std::size_t>(n), frame)) return Io::ok;
    }
  }
  accept_peers();
  for (int scanned = 0; scanned < peers_;) {
    const int i = next_peer_ % peers_;
    ssize_t n = ::recv(peer_fd_[i], bytes, sizeof bytes, MSG_DONTWAIT);
    if (n < 0 && (errno == EAGAIN || errno == EWOULDBLOCK)) {
      ++scanned;
      next_peer_ = i + 1;
      continue;
    }
    if (n <= 0) {  // the peer went away
      drop_peer(i);
      scanned = 0;
      continue;
    }
    const int from = peer_fd_[i];
    for (int k = peers_ - 1; k >= 0; --k) {  // the bus relays to everyone else
      if (peer_fd_[k] == from) continue;
      if (::send(peer_fd_[k], bytes, static_cast<std::size_t>(n), MSG_DONTWAIT | MSG_NOSIGNAL) < 0 && gone(errno))
        drop_peer(k);
    }
    next_peer_ = i + 1;
    if (decode(bytes, static_cast<std::size_t>(n), frame)) return Io::ok;
    scanned = 0;
  }
  return Io::empty;
}

}  // namespace hapfluid::device
