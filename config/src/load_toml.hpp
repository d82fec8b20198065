// Parses TOML text into a table, turning a syntax error into a ConfigError with file and line.
#pragma once

#include <filesystem>
#include <string>

#include <toml++/toml.h>

namespace hapfluid::config::detail {

toml::table parse_toml(const std::string& text, const std::filesystem::path& file);
std::string read_text_file(const std::filesystem::path& file, const char* what);

}  // namespace hapfluid::config::detail
