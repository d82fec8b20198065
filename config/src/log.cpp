#include "hapfluid/config/log.hpp"

#include <sys/stat.h>
#include <unistd.h>

#include <atomic>
#include <cerrno>
#include <cstdarg>
#include <cstdio>
#include <cstdlib>
#include <mutex>
#include <string>

namespace hapfluid::log {
namespace {

struct State {
  std::atomic<int> level{static_cast<int>(Level::info)};
  bool journal = false;
  std::string bad_environment;  // HAPFLUID_LOG_LEVEL's text when it names no level
  std::atomic<bool> said_bad_environment{false};
  std::mutex mutex;  // guards the three below: the tool is set at start-up, a capture by tests
  std::string tool;
  bool capturing = false;
  std::string captured;

  State() {
    if (const char* stream = std::getenv("JOURNAL_STREAM")) {
      unsigned long long dev = 0, ino = 0;
      struct stat st {};
      journal = std::sscanf(stream, "%llu:%llu", &dev, &ino) == 2 && fstat(STDERR_FILENO, &st) == 0 &&
                static_cast<unsigned long long>(st.st_dev) == dev && static_cast<unsigned long long>(st.st_ino) == ino;
    }
    if (const char* text = std::getenv("HAPFLUID_LOG_LEVEL")) {
      if (const auto parsed = parse_level(text))
        level = static_cast<int>(*parsed);
      else
        bad_environment = text;
    }
  }
};

State& state() {
  static State s;
  return s;
}

void write_all(const std::string& bytes) {
  std::size_t done = 0;
  while (done < bytes.size()) {
    const ssize_t n = ::write(STDERR_FILENO, bytes.data() + done, bytes.size() - done);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) return;  // stderr closed or full: nothing better to tell anyone
    done += static_cast<std::size_t>(n);
  }
}

void vwrite(Level level, const char* format, va_list args) {
  if (!enabled(level)) return;
  char small[512];
  va_list copy;
  va_copy(copy, args);
  const int n = std::vsnprintf(small, sizeof small, format, copy);
  va_end(copy);
  if (n < 0) return;
  if (static_cast<std::size_t>(n) < sizeof small) {
    write(level, std::string_view(small, static_cast<std::size_t>(n)));
    return;
  }
  std::string text(static_cast<std::size_t>(n) + 1, '\0');
  std::vsnprintf(text.data(), text.size(), format, args);
  text.resize(static_cast<std::size_t>(n));
  write(level, text);
}

}  // namespace

const char* to_string(Level level) {
  switch (level) {
    case Level::error: return "error";
    case Level::warning: return "warning";
    case Level::notice: return "notice";
    case Level::info: return "info";
    case Level::debug: return "debug";
  }
  return "info";
}

std::optional<Level> parse_level(std::string_view text) {
  for (Level l : {Level::error, Level::warning, Level::notice, Level::info, Level::debug})
    if (text == to_string(l)) return l;
  return std::nullopt;
}

const char* level_names() { return "error, warning, notice, info, debug"; }

void set_tool(std::string_view tool) {
  State& s = state();
  {
    std::lock_guard lock(s.mutex);
    s.tool.assign(tool);
  }
  // Said once the message can name its tool.
  if (!s.bad_environment.empty() && !s.said_bad_environment.exchange(true))
    write(Level::warning, "HAPFLUID_LOG_LEVEL \"" + s.bad_environment + "\" is not a level (" + level_names() +
                              "); logging at info");
}

void set_level(Level level) { state().level = static_cast<int>(level); }
Level level() { return static_cast<Level>(state().level.load()); }
bool enabled(Level level) { return static_cast<int>(level) <= state().level.load(std::memory_order_relaxed); }

std::string detail::format(Level level, std::string_view tool, bool journal, std::string_view message) {
  while (!message.empty() && message.back() == '\n') message.remove_suffix(1);
  const std::string priority = journal ? "<" + std::to_string(static_cast<int>(level)) + ">" : "";
  std::string out;
  out.reserve(message.size() + tool.size() + 16);
  std::size_t start = 0;
  for (bool first = true;; first = false) {
    const std::size_t end = message.find('\n', start);
    out += priority;
    if (first && !tool.empty()) out.append(tool).append(": ");
    out += message.substr(start, end == std::string_view::npos ? std::string_view::npos : end - start);
    out += '\n';
    if (end == std::string_view::npos) break;
    start = end + 1;
  }
  return out;
}

void write(Level level, std::string_view message) {
  if (!enabled(level)) return;
  State& s = state();
  std::string bytes;
  {
    std::lock_guard lock(s.mutex);
    bytes = detail::format(level, s.tool, s.journal, message);
    if (s.capturing) {
      s.captured += bytes;
      return;
    }
  }
  write_all(bytes);  // outside the lock: one write(2) keeps the line whole
}

Capture::Capture() {
  State& s = state();
  std::lock_guard lock(s.mutex);
  s.capturing = true;
  s.captured.clear();
}

Capture::~Capture() {
  State& s = state();
  std::lock_guard lock(s.mutex);
  s.capturing = false;
}

std::string Capture::text() const {
  State& s = state();
  std::lock_guard lock(s.mutex);
  return s.captured;
}

#define HAPFLUID_LOG_AT(name, level)        \
  void name(const char* format, ...) {      \
    va_list args;                           \
    va_start(args, format);                 \
    vwrite(level, format, args);            \
    va_end(args);                           \
  }
HAPFLUID_LOG_AT(error, Level::error)
HAPFLUID_LOG_AT(warning, Level::warning)
HAPFLUID_LOG_AT(notice, Level::notice)
HAPFLUID_LOG_AT(info, Level::info)
HAPFLUID_LOG_AT(debug, Level::debug)
#undef HAPFLUID_LOG_AT

}  // namespace hapfluid::log
