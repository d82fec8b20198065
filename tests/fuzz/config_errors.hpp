// The config library's error contract, checked on every ConfigError a harness catches: at least
// one problem, each naming the file it was given and saying why (config/include/.../errors.hpp).
#pragma once

#include <filesystem>

#include "fuzz_target.h"
#include "hapfluid/config/errors.hpp"

namespace hapfluid::fuzz {

inline void check_config_error(const config::ConfigError& error, const std::filesystem::path& file) {
  if (error.problems().empty()) hapfluid_fuzz_violated("a ConfigError without a problem");
  for (const config::Problem& p : error.problems()) {
    if (p.file != file.string()) hapfluid_fuzz_violated("a config problem that does not name its file");
    if (p.reason.empty()) hapfluid_fuzz_violated("a config problem without a reason");
    if (p.to_string().find(p.reason) == std::string::npos) hapfluid_fuzz_violated("a config message without its reason");
  }
}

}  // namespace hapfluid::fuzz
