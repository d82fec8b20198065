#include "hapfluid/config/errors.hpp"

#include <sstream>

namespace hapfluid::config {

std::string Problem::to_string() const {
  std::ostringstream out;
  out << file;
  if (line > 0) out << ':' << line;
  out << ": ";
  if (!key.empty()) {
    out << key;
    if (!value.empty()) out << " = " << value;
    out << ": ";
  }
  out << reason;
  return out.str();
}

static std::string join(const std::vector<Problem>& problems) {
  std::string text;
  for (const auto& p : problems) {
    if (!text.empty()) text += '\n';
    text += p.to_string();
  }
  return text;
}

ConfigError::ConfigError(std::vector<Problem> problems)
    : std::runtime_error(join(problems)), problems_(std::move(problems)) {}

}  // namespace hapfluid::config
