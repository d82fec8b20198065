// The JSON every executable writes (stats.json, benchmark records, device reports), through one
// library (nlohmann-json): key order as written, since a person reads these files too; the build
// that produced them; text that is always valid JSON.
#pragma once

#include <filesystem>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

namespace hapfluid::config {

using Json = nlohmann::ordered_json;

// Indented JSON text with a final newline. A string that is not UTF-8 (a path named in Latin-1)
// is written with U+FFFD for its bad bytes, not lost with the whole file; a non-finite number is
// written null.
std::string json_text(const Json& value);

// The same on one line, for records printed to a log or a pipe.
std::string json_line(const Json& value);

// A benchmark record as `make bench` reads it: {"bench", "build_id", "params", "metrics"}.
Json bench_record(const std::string& bench, Json params, Json metrics);

// Writes json_text(value) to `file` under a temporary name, then renames it: a reader never sees
// half a file. Throws std::runtime_error naming the file when it cannot be written.
void write_json_atomically(const std::filesystem::path& file, const Json& value);

}  // namespace hapfluid::config
