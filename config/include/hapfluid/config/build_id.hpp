// Which build produced a binary or an output: "<project version>+git.<git describe --dirty>",
// fixed at build time (cmake/build_id.cmake). `--version` prints it; JSON outputs record it.
#pragma once

namespace hapfluid::config {

const char* build_id();

}  // namespace hapfluid::config
