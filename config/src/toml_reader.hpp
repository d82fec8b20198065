// A reader over one TOML table that remembers which keys were asked for, so that unknown keys
// (usually typos) are reported, and that turns every bad value into a Problem naming the file,
// line, key path, value and reason instead of stopping at the first one.
#pragma once

#include <toml++/toml.h>

#include <functional>
#include <optional>
#include <set>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "hapfluid/config/errors.hpp"
#include "hapfluid/config/types.hpp"

namespace hapfluid::config::detail {

struct Diagnostics {
  std::string file;
  std::vector<Problem> problems;
  void add(int line, std::string key, std::string value, std::string reason) {
    problems.push_back({file, line, std::move(key), std::move(value), std::move(reason)});
  }
  void throw_if_any() const {
    if (!problems.empty()) throw ConfigError(problems);
  }
};

std::string describe(const toml::node& node);
int line_of(const toml::node& node);

class Reader {
 public:
  Reader(const toml::table& table, std::string path, Diagnostics& diag);

  const std::string& path() const { return path_; }
  std::string key_path(std::string_view key) const;
  int line() const { return line_of(*table_); }
  bool has(std::string_view key) const { return table_->contains(key); }
  Diagnostics& diagnostics() const { return *diag_; }

  // Each accessor marks the key as known, returns the default when it is absent, and records
  // a problem (and returns the default) when it has the wrong type or is not finite.
  double number(std::string_view key, double fallback);
  std::optional<double> optional_number(std::string_view key);
  double required_number(std::string_view key);
  long long integer(std::string_view key, long long fallback);
  bool boolean(std::string_view key, bool fallback);
  std::string string(std::string_view key, std::string fallback);
  std::optional<std::string> required_string(std::string_view key);
  Vec3 vec3(std::string_view key, Vec3 fallback);
  std::optional<Vec3> required_vec3(std::string_view key);
  Quat quaternion(std::string_view key, Quat fallback);  // normalised; zero is an error
  // Reads an optional number over `value` (its default) and requires it to be > 0.
  void positive(std::string_view key, double& value);

  template <class Enum>
  Enum choice(std::string_view key, Enum fallback,
              std::initializer_list<std::pair<const char*, Enum>> options);

  std::optional<Reader> table(std::string_view key);
  // An array of tables; each element's path uses its "name" key when it has one.
  std::vector<Reader> tables(std::string_view key);

  // A value check: records "key = value: reason" when ok is false.
  void check(std::string_view key, bool ok, const std::string& reason);
  void problem(std::string_view key, const std::string& reason);

  // Records every key that no accessor asked for.
  void finish();

 private:
  const toml::node* get(std::string_view key);
  void wrong_type(std::string_view key, const toml::node& node, const std::string& expected);

  const toml::table* table_;
  std::string path_;
  Diagnostics* diag_;
  std::set<std::string, std::less<>> known_;
};

template <class Enum>
Enum Reader::choice(std::string_view key, Enum fallback,
                    std::initializer_list<std::pair<const char*, Enum>> options) {
  const toml::node* node = get(key);
  if (!node) return fallback;
  const auto* text = node->as_string();
  std::string allowed;
  for (const auto& [name, value] : options) {
    if (text && text->get() == name) return value;
    allowed += allowed.empty() ? "" : ", ";
    allowed += '"' + std::string(name) + '"';
  }
  diag_->add(line_of(*node), key_path(key), describe(*node), "must be one of " + allowed);
  return fallback;
}

}  // namespace hapfluid::config::detail
