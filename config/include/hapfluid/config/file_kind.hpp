// Whether a TOML file is a rig or a scene, from the keys of its schemas (docs/config-reference.md):
// a rig has an [rt] table or devices with a transport; a scene a [domain], [fluid], [time],
// duration_s, description, bodies or couplings, or devices with a source, motion or start pose.
// A file with devices and no key of either is a rig (the only schema it can still satisfy).
#pragma once

#include <filesystem>
#include <string>

namespace hapfluid::config {

enum class FileKind { rig, scene };

// Throws ConfigError naming the file when it cannot be read or parsed, or when its keys belong
// to both schemas or to neither (then the caller must be told the kind, e.g. --kind).
FileKind detect_file_kind(const std::filesystem::path& file);
FileKind detect_file_kind_of_text(const std::string& toml_text, const std::filesystem::path& file_for_messages);

}  // namespace hapfluid::config
