// The log of every hapfluid process: one message per call on stderr, "<tool>: <message>", with
// levels. Under systemd (stderr is the journal's stream) every line carries its syslog priority as
// an sd-daemon prefix ("<4>"), so `journalctl -p warning` filters what a service said.
//
// Messages below the level set by `--log-level` (every tool, command_line.hpp) or the environment
// variable HAPFLUID_LOG_LEVEL are dropped. A message is written with one write(2), so lines of
// several threads never interleave. The 1 kHz loop thread never logs: a message formats and
// allocates; its faults travel as flags and counters that the supervisor thread reports.
#pragma once

#include <optional>
#include <sstream>
#include <string>
#include <string_view>

namespace hapfluid::log {

// The syslog priorities of sd-daemon(3).
enum class Level : int { error = 3, warning = 4, notice = 5, info = 6, debug = 7 };

const char* to_string(Level level);
// "error", "warning", "notice", "info" or "debug"; nothing for any other text.
std::optional<Level> parse_level(std::string_view text);
// The names parse_level takes, for usage texts: "error, warning, notice, info, debug".
const char* level_names();

// The tool name every message starts with (the executable's name; command_line.hpp sets it).
void set_tool(std::string_view tool);
void set_level(Level level);
Level level();
bool enabled(Level level);

// One message; it may span lines (the journal gets the priority on each of them).
void write(Level level, std::string_view message);

void error(const char* format, ...) __attribute__((format(printf, 1, 2)));
void warning(const char* format, ...) __attribute__((format(printf, 1, 2)));
void notice(const char* format, ...) __attribute__((format(printf, 1, 2)));
void info(const char* format, ...) __attribute__((format(printf, 1, 2)));
void debug(const char* format, ...) __attribute__((format(printf, 1, 2)));

// While one lives, messages go to it instead of stderr (tests read what a part said).
class Capture {
 public:
  Capture();
  ~Capture();
  Capture(const Capture&) = delete;
  Capture& operator=(const Capture&) = delete;
  std::string text() const;
};

namespace detail {
// The bytes of one message: "<tool>: " before its first line; in the journal, "<priority>" before
// every line, since journald reads each line as a record of its own.
std::string format(Level level, std::string_view tool, bool journal, std::string_view message);
}  // namespace detail

// A message built with <<, written when the statement ends:  log::Line(Level::info) << "n " << n;
class Line {
 public:
  explicit Line(Level level) : level_(level), on_(enabled(level)) {}
  Line(const Line&) = delete;
  Line& operator=(const Line&) = delete;
  ~Line() {
    if (on_) write(level_, text_.str());
  }
  template <class T>
  Line& operator<<(const T& value) {
    if (on_) text_ << value;
    return *this;
  }
  // Manipulators (std::fixed, std::setprecision) reach the text as well.
  Line& operator<<(std::ostream& (*manipulator)(std::ostream&)) {
    if (on_) text_ << manipulator;
    return *this;
  }

 private:
  Level level_;
  bool on_;
  std::ostringstream text_;
};

}  // namespace hapfluid::log
