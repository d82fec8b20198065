// Configuration errors: every problem names the file, the key path, the offending value and the
// reason, so a user can fix a rig or scene file without reading the code.
#pragma once

#include <stdexcept>
#include <string>
#include <vector>

namespace hapfluid::config {

struct Problem {
  std::string file;
  int line = 0;         // 0 when the problem has no source position (e.g. a missing key)
  std::string key;      // dotted key path, e.g. "devices.left.max_force_n"
  std::string value;    // the offending value as written, empty when missing
  std::string reason;   // e.g. "must be > 0"

  // "rig.toml:12: devices.left.max_force_n = -3: must be > 0"
  std::string to_string() const;
};

// Thrown by the loaders after the whole file was read, carrying every problem found in it.
class ConfigError : public std::runtime_error {
 public:
  explicit ConfigError(std::vector<Problem> problems);
  const std::vector<Problem>& problems() const { return problems_; }

 private:
  std::vector<Problem> problems_;
};

}  // namespace hapfluid::config
