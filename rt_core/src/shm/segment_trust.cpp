// Segment ownership checks and fallback names (see segment_trust.hpp).
#include "segment_trust.hpp"

#include <dirent.h>
#include <pwd.h>
#include <unistd.h>

#include <atomic>
#include <cstdio>
#include <cstring>
#include <random>

namespace hapfluid::shm::detail {
namespace {
// glibc's shm_open keeps its objects here.
constexpr const char* kShmDirectory = "/dev/shm";
constexpr std::size_t kFallbackHexDigits = 16;

bool is_hex_suffix(const char* s) {
  if (std::strlen(s) != kFallbackHexDigits) return false;
  for (; *s; ++s)
    if (!((*s >= '0' && *s <= '9') || (*s >= 'a' && *s <= 'f'))) return false;
  return true;
}
}  // namespace

std::string describe_user(uid_t uid) {
  std::string text = "uid " + std::to_string(uid);
  char buffer[1024];
  struct passwd entry {};
  struct passwd* found = nullptr;
  if (::getpwuid_r(uid, &entry, buffer, sizeof buffer, &found) == 0 && found)
    text += std::string(" (") + found->pw_name + ")";
  return text;
}

namespace {
std::atomic<uid_t> g_trusted_writer{static_cast<uid_t>(-1)};
}  // namespace

bool trusted_owner(uid_t uid) {
  return uid == ::geteuid() || uid == 0 || uid == g_trusted_writer.load(std::memory_order_relaxed);
}

std::string trust_problem(const struct stat& st) {
  const uid_t self = ::geteuid();
  if (!S_ISREG(st.st_mode)) return "is not a regular shared-memory object";
  if (!trusted_owner(st.st_uid))
    return "is owned by " + describe_user(st.st_uid) + ", not by " +
           (self == 0 ? std::string("root (this service's user)")
                      : "this service's user (" + describe_user(self) + ") or root") +
           (g_trusted_writer.load() != static_cast<uid_t>(-1)
                ? " or the writers' user (" + describe_user(g_trusted_writer.load()) + ")"
                : std::string());
  if (st.st_mode & (S_IWGRP | S_IWOTH)) {
    char mode[16];
    std::snprintf(mode, sizeof mode, "%04o", unsigned(st.st_mode & 07777));
    return std::string("has mode ") + mode + ": others than its owner may write it (a channel is 0640)";
  }
  return {};
}

std::vector<std::string> fallback_names(const std::string& name) {
  std::vector<std::string> names;
  DIR* dir = ::opendir(kShmDirectory);
  if (!dir) return names;
  const std::string stem = name.substr(1) + ".";
  while (const dirent* entry = ::readdir(dir)) {
    if (std::strncmp(entry->d_name, stem.c_str(), stem.size()) == 0 && is_hex_suffix(entry->d_name + stem.size()))
      names.push_back("/" + std::string(entry->d_name));
  }
  ::closedir(dir);
  return names;
}

std::string new_fallback_name(const std::string& name) {
  std::random_device random;
  char hex[kFallbackHexDigits + 1];
  std::snprintf(hex, sizeof hex, "%08x%08x", unsigned(random()), unsigned(random()));
  return name + "." + hex;
}

}  // namespace hapfluid::shm::detail

namespace hapfluid::shm {
void trust_writer_uid(uid_t uid) { detail::g_trusted_writer.store(uid, std::memory_order_relaxed); }
}  // namespace hapfluid::shm
