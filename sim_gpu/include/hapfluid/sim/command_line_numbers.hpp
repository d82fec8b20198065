// Strict parsing of haptic-sim's numeric options (batch and live): the whole argument must be
// the number, nothing is rounded or truncated. Each parser returns "" on success, else the
// reason; the CLI11 validators below put it in the tool's one-line usage error:
//   haptic-sim: --threads: must be a whole number in 1..256, not "2.5" (haptic-sim --help for usage)
#pragma once

#include <charconv>
#include <cmath>
#include <cstdio>
#include <string>
#include <string_view>
#include <system_error>

#include <CLI/CLI.hpp>

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

// The same rules as CLI11 validators: "must be a whole number in 1..256, not "2.5"".
inline CLI::Validator whole_number_in(int lo, int hi) {
  return CLI::Validator(
      [lo, hi](std::string& text) -> std::string {
        int value = 0;
        const std::string reason = parse_whole_number(text, lo, hi, value);
        return reason.empty() ? reason : reason + ", not \"" + text + "\"";
      },
      "INT in " + std::to_string(lo) + ".." + std::to_string(hi));
}

inline CLI::Validator seconds_from(double lo, bool lo_excluded) {
  return CLI::Validator(
      [lo, lo_excluded](std::string& text) -> std::string {
        double value = 0;
        const std::string reason = parse_seconds(text, lo, lo_excluded, value);
        return reason.empty() ? reason : reason + ", not \"" + text + "\"";
      },
      std::string("SECONDS ") + (lo_excluded ? "> " : ">= ") + detail::format_bound(lo));
}

}  // namespace hapfluid::sim
