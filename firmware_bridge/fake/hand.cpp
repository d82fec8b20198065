#include "hand.hpp"

#include <poll.h>
#include <unistd.h>

#include <cmath>
#include <sstream>
#include <stdexcept>

#include "hapfluid/config/scene.hpp"

namespace hapfluid::fake {

config::ScriptedMotion builtin_motion(const std::string& name, const config::Pose& start) {
  config::ScriptedMotion m;
  m.start = start;
  config::MotionSegment s;
  if (name == "hold") return m;
  if (name == "stir") {  // back and forth through the fluid: 3 cm at 1 Hz along x
    s.kind = config::MotionKind::oscillate;
    s.axis = {1, 0, 0};
    s.amplitude_m = 0.03;
    s.frequency_hz = 1.0;
  } else if (name == "pour") {  // tip the container 60 degrees about x, hold, bring it back
    s.kind = config::MotionKind::tilt;
    s.axis = {1, 0, 0};
    s.angle_rad = M_PI / 3;
    s.hold_s = 1.0;
    s.start_s = 0.5;
    s.stop_s = 4.5;
    s.pivot_offset_m = {0, 0, 0.05};
  } else if (name == "spin") {  // spin the glass about its vertical axis at 3 rad/s
    s.kind = config::MotionKind::spin;
    s.axis = {0, 0, 1};
    s.angular_speed_rad_s = 3.0;
    s.ramp_s = 0.5;
    s.start_s = 0.0;
    s.stop_s = 1e6;
  } else if (name == "tilt") {  // tilt the bucket 30 degrees about y and back
    s.kind = config::MotionKind::tilt;
    s.axis = {0, 1, 0};
    s.angle_rad = M_PI / 6;
    s.hold_s = 0.5;
    s.start_s = 0.0;
    s.stop_s = 3.0;
  } else {
    throw std::invalid_argument("unknown motion '" + name + "': choose hold, stir, pour, spin, tilt, "
                                "interactive or scene:FILE:DEVICE");
  }
  m.segments.push_back(s);
  return m;
}

config::ScriptedMotion scene_motion(const std::string& scene_file, const std::string& device) {
  config::Scene scene = config::load_scene(scene_file);
  const config::SceneDevice* d = scene.find_device(device);
  if (!d) throw std::invalid_argument(scene_file + ": no device named '" + device + "'");
  return d->motion;
}

void Hand::read_stdin() {
  pollfd p{0, POLLIN, 0};
  while (::poll(&p, 1, 0) > 0 && (p.revents & POLLIN)) {
    char buffer[256];
    ssize_t n = ::read(0, buffer, sizeof buffer);
    if (n <= 0) { interactive_ = false; return; }
    pending_.append(buffer, static_cast<std::size_t>(n));
    for (std::size_t eol; (eol = pending_.find('\n')) != std::string::npos; pending_.erase(0, eol + 1)) {
      std::istringstream line(pending_.substr(0, eol));
      config::Vec3 v;
      if (line >> v.x >> v.y >> v.z) offset_ = v;
    }
  }
}

config::PoseTwist Hand::target(double t_s) {
  config::PoseTwist p = config::evaluate_motion(motion_, t_s);
  if (interactive_) {
    read_stdin();
    p.pose.position_m.x += offset_.x;
    p.pose.position_m.y += offset_.y;
    p.pose.position_m.z += offset_.z;
  }
  return p;
}

}  // namespace hapfluid::fake
