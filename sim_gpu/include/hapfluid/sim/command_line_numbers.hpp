// Strict parsing of haptic-sim's numeric options (batch and live): the whole argument must be
// the number, nothing is rounded or truncated. Each parser returns "" on success, else the
// reason, which the caller prints after the option and its value:
//   haptic-sim: --threads 2.5: must be a whole number in 1..256
#pragma once

#include <charconv>
#include <cmath>
#include <cstdio>
#include <ostream>
#include <string>
#include <string_view>
#include <system_error>

namespace hapfluid::sim {

namespace detail {
inline std::string format_bound(double v) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%g", v);
  return buf;
}
inline bool parses_whole(std::string_view text, double& out) {
  const auto [end, ec] = std::from_chars(text.data(), text.data() + text.size(), out);
  return ec == std::errc() && end == text.data() + text.size();
}
}  // namespace detail

// A whole number in [lo, hi], in decimal digits with an optional leading '-'.
inline std::string parse_whole_number(std::string_view text, int lo, int hi, int& out) {
  const std::string range = "a whole number in " + std::to_string(lo) + ".." + std::to_string(hi);
  int value = 0;
  const auto [end, ec] = std::from_chars(text.data(), text.data() + text.size(), value);
  double as_real = 0;
  if (ec == std::errc() && end == text.data() + text.size()) {
    if (value < lo || value > hi) return "must be " + range;
    out = value;
    return "";
  }
  if (detail::parses_whole(text, as_real)) return "must be " + range;  // a fraction, or beyond int
  return "not a number (must be " + range + ")";
}

// A finite number of seconds, >= lo (or > lo when lo_excluded).
inline std::string parse_seconds(std::string_view text, double lo, bool lo_excluded, double& out) {
  const std::string bound = (lo_excluded ? "> " : ">= ") + detail::format_bound(lo);
  double value = 0;
  if (!detail::parses_whole(text, value)) return "not a number (must be a number of seconds " + bound + ")";
  if (!std::isfinite(value)) return "must be a finite number of seconds " + bound;
  if (lo_excluded ? !(value > lo) : !(value >= lo)) return "must be " + bound + " s";
  out = value;
  return "";
}

// True when reason is empty (the value was accepted); else prints
// "haptic-sim: <option> <value>: <reason>" to err.
inline bool accepted(std::ostream& err, std::string_view option, std::string_view value, const std::string& reason) {
  if (reason.empty()) return true;
  err << "haptic-sim: " << option << " " << value << ": " << reason << "\n";
  return false;
}

}  // namespace hapfluid::sim
