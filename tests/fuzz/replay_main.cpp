// The normal build's driver for a harness (libFuzzer's main stands in for it in the fuzz build):
// runs every input file once, in name order.
//   fuzz_replay_<target> [--all-accepted] FILE_OR_DIR...
// --all-accepted fails unless the code under test accepted every input: the seed corpus must be
// valid inputs, or fuzzing would start from nothing.
#include <algorithm>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <string>
#include <vector>

#include "fuzz_target.h"

int main(int argc, char** argv) {
  bool all_accepted = false;
  std::vector<std::filesystem::path> files;
  for (int i = 1; i < argc; ++i) {
    if (std::strcmp(argv[i], "--all-accepted") == 0) {
      all_accepted = true;
      continue;
    }
    const std::filesystem::path path = argv[i];
    if (std::filesystem::is_directory(path)) {
      for (const auto& entry : std::filesystem::directory_iterator(path))
        if (entry.is_regular_file()) files.push_back(entry.path());
    } else {
      files.push_back(path);
    }
  }
  std::sort(files.begin(), files.end());
  if (files.empty()) {
    std::fprintf(stderr, "usage: %s [--all-accepted] FILE_OR_DIR... (no input files given or found)\n", argv[0]);
    return 2;
  }
  std::vector<std::string> refused;
  for (const auto& file : files) {
    std::ifstream in(file, std::ios::binary);
    if (!in) {
      std::fprintf(stderr, "%s: cannot read\n", file.c_str());
      return 2;
    }
    const std::vector<char> bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    const std::uint64_t before = hapfluid_fuzz_accepted;
    LLVMFuzzerTestOneInput(reinterpret_cast<const std::uint8_t*>(bytes.data()), bytes.size());
    if (hapfluid_fuzz_accepted == before) refused.push_back(file.string());
  }
  std::printf("%s: %zu inputs, %zu accepted, no crash\n", argv[0], files.size(), files.size() - refused.size());
  if (all_accepted && !refused.empty()) {
    for (const auto& file : refused) std::fprintf(stderr, "not accepted: %s\n", file.c_str());
    return 1;
  }
  return 0;
}
