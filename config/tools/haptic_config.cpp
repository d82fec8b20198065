// haptic-config: validates rig and scene files before a rig ever moves.
//
//   haptic-config check FILE...                 validate each file (rig or scene, told by its keys)
//   haptic-config check --rig R SCENE...        also check that the scenes' live devices exist in rig R
//   haptic-config check --kind scene FILE...    read every FILE as a scene (or rig), whatever its keys
//
// Prints one line per problem ("file:line: key = value: reason") and exits 1 if there was any;
// a usage error exits 2.
#include <cstdio>
#include <string>
#include <vector>

#include "hapfluid/config/command_line.hpp"
#include "hapfluid/config/errors.hpp"
#include "hapfluid/config/file_kind.hpp"
#include "hapfluid/config/log.hpp"
#include "hapfluid/config/rig.hpp"
#include "hapfluid/config/scene.hpp"

using namespace hapfluid::config;

int main(int argc, char** argv) {
  CLI::App app{"Validates hapfluid rig and scene files (TOML, SI units; docs/config-reference.md).", "haptic-config"};
  apply_convention(app);
  app.require_subcommand(1, 1);
  CLI::App* check = app.add_subcommand("check", "validate each file; one line per problem, exit 1 if any");
  std::string rig_path, kind_name = "auto";
  std::vector<std::string> files;
  check->add_option("--rig", rig_path, "a rig file: also check that the scenes' rig devices exist in it");
  check->add_option("--kind", kind_name, "read every FILE as this kind, or tell each from its keys")
      ->check(CLI::IsMember({"auto", "rig", "scene"}))
      ->capture_default_str();
  check->add_option("files", files, "rig and scene files (TOML)");
  if (const int code = parse_command_line(app, argc, argv); code >= 0) return code;
  if (!rig_path.empty()) files.insert(files.begin(), rig_path);
  if (files.empty()) {
    hapfluid::log::error("check: no FILE given (haptic-config --help for usage)");
    return kUsageExitCode;
  }

  int bad = 0;
  Rig rig;
  bool have_rig = false;
  for (const auto& file : files) {
    try {
      FileKind kind = file == rig_path ? FileKind::rig : kind_name == "rig" ? FileKind::rig
                      : kind_name == "scene"                               ? FileKind::scene
                                                                           : detect_file_kind(file);
      if (kind == FileKind::scene) {
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
      // One message per file: its problems, one per line (each at error priority in the journal).
      hapfluid::log::Line message(hapfluid::log::Level::error);
      const char* separator = "";
      for (const auto& p : error.problems()) message << separator << p.to_string(), separator = "\n";
    }
  }
  if (bad) hapfluid::log::error("%d of %zu files have errors", bad, files.size());
  return bad ? 1 : 0;
}
