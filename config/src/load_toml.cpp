#include "load_toml.hpp"

#include <fstream>
#include <sstream>

#include "hapfluid/config/errors.hpp"

namespace hapfluid::config::detail {

toml::table parse_toml(const std::string& text, const std::filesystem::path& file) {
  try {
    return toml::parse(text, file.string());
  } catch (const toml::parse_error& error) {
    Problem p;
    p.file = file.string();
    p.line = static_cast<int>(error.source().begin.line);
    p.reason = "TOML syntax error: " + std::string(error.description());
    throw ConfigError({p});
  }
}

std::string read_text_file(const std::filesystem::path& file, const char* what) {
  std::ifstream in(file, std::ios::binary);
  if (!in) {
    Problem p;
    p.file = file.string();
    p.reason = std::string("cannot open ") + what + " file (missing or unreadable)";
    throw ConfigError({p});
  }
  std::ostringstream text;
  text << in.rdbuf();
  return text.str();
}

}  // namespace hapfluid::config::detail
