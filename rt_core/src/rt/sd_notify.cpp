#include "hapfluid/rt/sd_notify.hpp"

#include <sys/socket.h>
#include <sys/un.h>
#include <unistd.h>

#include <cstddef>
#include <cstdlib>
#include <cstring>

namespace hapfluid::rt {

SdNotifier::SdNotifier() {
  const char* socket_path = std::getenv("NOTIFY_SOCKET");
  if (socket_path && (socket_path[0] == '/' || socket_path[0] == '@') &&
      std::strlen(socket_path) < sizeof(sockaddr_un::sun_path)) {
    path_ = socket_path;
    fd_ = ::socket(AF_UNIX, SOCK_DGRAM | SOCK_CLOEXEC, 0);
  }
  if (const char* usec = std::getenv("WATCHDOG_USEC")) {
    // WATCHDOG_PID, when set, must name us.
    const char* pid = std::getenv("WATCHDOG_PID");
    if (!pid || std::atoll(pid) == ::getpid()) watchdog_interval_ns_ = std::strtoull(usec, nullptr, 10) * 1000 / 2;
  }
}

SdNotifier::~SdNotifier() {
  if (fd_ >= 0) ::close(fd_);
}

bool SdNotifier::send(const std::string& message) {
  if (fd_ < 0) return false;
  sockaddr_un address{};
  address.sun_family = AF_UNIX;
  std::memcpy(address.sun_path, path_.data(), path_.size());
  socklen_t length = static_cast<socklen_t>(offsetof(sockaddr_un, sun_path) + path_.size());
  if (path_[0] == '@') address.sun_path[0] = '\0';
  return ::sendto(fd_, message.data(), message.size(), MSG_NOSIGNAL, reinterpret_cast<sockaddr*>(&address),
                  length) == static_cast<ssize_t>(message.size());
}

}  // namespace hapfluid::rt
