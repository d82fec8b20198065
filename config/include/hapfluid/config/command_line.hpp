// The command-line convention of every hapfluid executable, on CLI11:
//  - `--help` prints the usage to stdout and exits 0; `--version` prints "<tool> <build id>";
//  - a usage error exits 2 with one line on stderr naming the option and what was wrong;
//  - `--log-level` sets what the log (log.hpp) lets through.
#pragma once

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <string>

#include <CLI/CLI.hpp>

#include "hapfluid/config/build_id.hpp"
#include "hapfluid/config/log.hpp"

namespace hapfluid::config {

inline constexpr int kUsageExitCode = 2;

namespace detail {
// A number that `accept` takes; otherwise "must be a number <requirement>, not "<text>"".
template <class Accept>
CLI::Validator number_validator(Accept accept, const std::string& requirement, const std::string& description) {
  return CLI::Validator(
      [accept, requirement](std::string& text) -> std::string {
        double value = 0;
        if (CLI::detail::lexical_cast(text, value) && accept(value)) return {};
        return "must be a number " + requirement + ", not \"" + text + "\"";
      },
      description);
}
}  // namespace detail

// A finite number >= 0 (a duration in seconds, a count), said in those words when it is not.
inline CLI::Validator non_negative_number(const std::string& unit) {
  return detail::number_validator([](double v) { return std::isfinite(v) && v >= 0; }, "of " + unit + " >= 0",
                                  unit + " >= 0");
}

// A finite number > 0 (a rate, a scale), said in those words when it is not.
inline CLI::Validator positive_number(const std::string& unit) {
  return detail::number_validator([](double v) { return std::isfinite(v) && v > 0; }, "of " + unit + " > 0",
                                  unit + " > 0");
}

// A number in [lo, hi] (a size, an angle, a count), said with its bounds when it is not.
inline CLI::Validator number_in(double lo, double hi) {
  char bounds[64];
  std::snprintf(bounds, sizeof bounds, "[%g, %g]", lo, hi);
  return detail::number_validator([lo, hi](double v) { return v >= lo && v <= hi; }, std::string("in ") + bounds,
                                  std::string("in ") + bounds);
}

// "X,Y,Z": three finite numbers and nothing else (a force, a torque, a position).
inline bool parse_three_numbers(const std::string& text, double v[3]) {
  const char* p = text.c_str();
  for (int k = 0; k < 3; ++k) {
    char* end = nullptr;
    v[k] = std::strtod(p, &end);
    if (end == p || !std::isfinite(v[k])) return false;
    p = end;
    if (k < 2 && *p++ != ',') return false;
  }
  return *p == '\0';
}

inline CLI::Validator three_numbers() {
  return CLI::Validator(
      [](std::string& text) -> std::string {
        double v[3];
        return parse_three_numbers(text, v) ? std::string() : "expected three comma-separated numbers, not \"" + text + "\"";
      },
      "X,Y,Z");
}

// The convention's parts that live on the App; call before adding options:
//  - `--version`;
//  - `--log-level`, and the log's messages named after the tool;
//  - an option given twice takes its last value, so a launcher can append overrides.
inline void apply_convention(CLI::App& app) {
  log::set_tool(app.get_name());
  app.option_defaults()->multi_option_policy(CLI::MultiOptionPolicy::TakeLast);
  app.set_version_flag("--version", app.get_name() + " " + build_id(), "print the build id and exit");
  app.add_option_function<std::string>(
         "--log-level",
         [](const std::string& text) {
           if (const auto level = log::parse_level(text)) log::set_level(*level);
         },
         std::string("messages at this level and above: ") + log::level_names() +
             " (default: $HAPFLUID_LOG_LEVEL, else info)")
      ->check(CLI::Validator(
          [](std::string& text) -> std::string {
            if (log::parse_level(text)) return {};
            return "must be one of " + std::string(log::level_names()) + ", not \"" + text + "\"";
          },
          "LEVEL"));
}

// Parses argv into `app`. Returns -1 when the tool should go on, else the exit code to return
// from main (--help and --version printed, or a usage error reported).
inline int parse_command_line(CLI::App& app, int argc, const char* const* argv) {
  try {
    app.parse(argc, argv);
    return -1;
  } catch (const CLI::CallForHelp&) {
    std::fputs(app.help().c_str(), stdout);
    return 0;
  } catch (const CLI::CallForAllHelp&) {
    std::fputs(app.help("", CLI::AppFormatMode::All).c_str(), stdout);
    return 0;
  } catch (const CLI::CallForVersion& version) {
    std::printf("%s\n", version.what());
    return 0;
  } catch (const CLI::ParseError& error) {
    log::error("%s (%s --help for usage)", error.what(), app.get_name().c_str());
    return kUsageExitCode;
  }
}

}  // namespace hapfluid::config
