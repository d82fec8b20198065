// haptic-config: validates rig and scene files before a rig ever moves.
//
//   haptic-config check FILE...          validate each file (rig or scene, told apart by content)
//   haptic-config check --rig R SCENE... also check that the scenes' live devices exist in rig R
//
// Prints one line per problem ("file:line: key = value: reason") and exits 1 if there was any.
#include <cstdio>
#include <cstring>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "hapfluid/config/errors.hpp"
#include "hapfluid/config/rig.hpp"
#include "hapfluid/config/scene.hpp"

using namespace hapfluid::config;

namespace {

int usage() {
  std::fprintf(stderr,
               "usage: haptic-config check [--rig RIG.toml] FILE...\n"
               "  Validates hapfluid rig and scene files (TOML, SI units).\n");
  return 2;
}

// A scene has a [fluid] or [domain] table; anything else is read as a rig.
bool looks_like_scene(const std::string& path) {
  std::ifstream in(path);
  std::string line;
  while (std::getline(in, line)) {
    size_t start = line.find_first_not_of(" \t");
    if (start == std::string::npos) continue;
    if (line.compare(start, 7, "[fluid]") == 0 || line.compare(start, 8, "[domain]") == 0 ||
        line.compare(start, 6, "[fluid") == 0)
      return true;
  }
  return false;
}

}  // namespace

int main(int argc, char** argv) {
  if (argc < 3 || std::strcmp(argv[1], "check") != 0) return usage();
  std::string rig_path;
  std::vector<std::string> files;
  for (int i = 2; i < argc; ++i) {
    if (std::strcmp(argv[i], "--rig") == 0 && i + 1 < argc) {
      rig_path = argv[++i];
      files.push_back(rig_path);
    } else if (argv[i][0] == '-') {
      return usage();
    } else {
      files.push_back(argv[i]);
    }
  }
  if (files.empty()) return usage();

  int bad = 0;
  Rig rig;
  bool have_rig = false;
  for (const auto& file : files) {
    try {
      if (looks_like_scene(file)) {
        Scene scene = load_scene(file);
        std::vector<Problem> problems;
        if (have_rig) {
          for (const auto& d : scene.devices)
            if (d.source == DeviceSource::rig && !rig.find_device(d.rig_device))
              problems.push_back({file, 0, "devices." + d.name + ".rig_device", "\"" + d.rig_device + "\"",
                                  "no device with that name in rig " + rig_path});
        }
        if (!problems.empty()) throw ConfigError(problems);
        std::printf("%s: ok (scene \"%s\": %zu bodies, %zu devices, %zu couplings)\n", file.c_str(), scene.name.c_str(),
                    scene.bodies.size(), scene.devices.size(), scene.couplings.size());
      } else {
        Rig loaded = load_rig(file);
        if (file == rig_path) {
          rig = loaded;
          have_rig = true;
        }
        std::printf("%s: ok (rig \"%s\": %zu devices)\n", file.c_str(), loaded.name.c_str(), loaded.devices.size());
      }
    } catch (const ConfigError& error) {
      ++bad;
      for (const auto& p : error.problems()) std::fprintf(stderr, "%s\n", p.to_string().c_str());
    }
  }
  if (bad) std::fprintf(stderr, "haptic-config: %d of %zu files have errors\n", bad, files.size());
  return bad ? 1 : 0;
}
