#include "hapfluid/config/file_kind.hpp"

#include <string>
#include <vector>

#include "hapfluid/config/errors.hpp"
#include "load_toml.hpp"

namespace hapfluid::config {
namespace {

const char* const kRigOnlyTop[] = {"rt"};
const char* const kSceneOnlyTop[] = {"domain", "fluid", "time", "duration_s", "description", "bodies", "couplings"};
const char* const kRigOnlyDevice[] = {"transport", "mapping", "wrench_mode", "passivity"};
const char* const kSceneOnlyDevice[] = {"source", "motion", "start_position_m", "rig_device"};

std::string joined(const std::vector<std::string>& keys) {
  std::string out;
  for (const auto& k : keys) out += (out.empty() ? "" : ", ") + k;
  return out;
}

}  // namespace

FileKind detect_file_kind_of_text(const std::string& text, const std::filesystem::path& file) {
  const toml::table root = detail::parse_toml(text, file);
  std::vector<std::string> rig, scene;
  for (const char* key : kRigOnlyTop)
    if (root.contains(key)) rig.push_back(key);
  for (const char* key : kSceneOnlyTop)
    if (root.contains(key)) scene.push_back(key);
  if (const toml::array* devices = root["devices"].as_array()) {
    for (const toml::node& d : *devices) {
      const toml::table* t = d.as_table();
      if (!t) continue;
      for (const char* key : kRigOnlyDevice)
        if (t->contains(key)) rig.push_back(std::string("devices.") + key);
      for (const char* key : kSceneOnlyDevice)
        if (t->contains(key)) scene.push_back(std::string("devices.") + key);
    }
  }
  if (!rig.empty() && scene.empty()) return FileKind::rig;
  if (rig.empty() && !scene.empty()) return FileKind::scene;
  // Devices and nothing else of either schema: a scene needs [domain] and [fluid], a rig only its
  // devices, so this is a rig that lacks something, and its own checks say what.
  if (rig.empty() && root.contains("devices")) return FileKind::rig;
  Problem p;
  p.file = file.string();
  if (rig.empty()) {
    p.reason = "neither a rig nor a scene: none of the keys of either schema is there (a rig has [[devices]], "
               "a scene [domain] and [fluid]); say which with --kind";
  } else {
    p.reason = "has keys of both a rig (" + joined(rig) + ") and a scene (" + joined(scene) +
               "): one file is one or the other; say which with --kind";
  }
  throw ConfigError({p});
}

FileKind detect_file_kind(const std::filesystem::path& file) {
  return detect_file_kind_of_text(detail::read_text_file(file, "rig or scene"), file);
}

}  // namespace hapfluid::config
