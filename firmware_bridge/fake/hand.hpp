// The fake device's "hand": where a person would move the handle. Either a scripted motion
// (the paper's scenarios, §6.4: stir, pour, spin, tilt; or any scene file's scripted device
// motion, keyframes included) evaluated by config::evaluate_motion, or interactive targets read
// from stdin ("x y z" in metres, one per line, relative to the start pose).
#pragma once

#include <string>

#include "hapfluid/config/motion.hpp"

namespace hapfluid::fake {

// Built-in motions: hold, stir, pour, spin, tilt. Throws std::invalid_argument naming the choices.
config::ScriptedMotion builtin_motion(const std::string& name, const config::Pose& start);
// A scene file's scripted motion of the named device. Throws with the scene's problems.
config::ScriptedMotion scene_motion(const std::string& scene_file, const std::string& device);

class Hand {
 public:
  explicit Hand(config::ScriptedMotion motion, bool interactive = false)
      : motion_(std::move(motion)), interactive_(interactive) {}
  config::PoseTwist target(double t_s);

 private:
  void read_stdin();
  config::ScriptedMotion motion_;
  bool interactive_;
  config::Vec3 offset_{};
  std::string pending_;
};

}  // namespace hapfluid::fake
