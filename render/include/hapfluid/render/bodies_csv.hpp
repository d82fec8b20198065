// The body history `haptic-sim --out DIR` writes as DIR/bodies.csv: one row per body per
// published frame, header `t,body,px,py,pz,qw,qx,qy,qz,...` (further columns such as velocities
// are ignored). The renderer needs each body's pose at a frame's time.
#pragma once

#include <filesystem>
#include <map>
#include <string>
#include <vector>

#include "hapfluid/render/frame_source.hpp"

namespace hapfluid::render {

struct BodySample {
  double t_s;
  BodyPose pose;
};

class BodyHistory {
 public:
  // Throws std::runtime_error("<file>: line N: ...") on a missing column or a malformed value.
  static BodyHistory load(const std::filesystem::path& file);
  // Pose at time t: interpolated between samples (lerp + slerp), held at the ends. False if the
  // body never appears.
  bool pose_at(const std::string& body, double t_s, BodyPose& pose) const;
  std::vector<std::string> bodies() const;

 private:
  std::map<std::string, std::vector<BodySample>> samples_;  // sorted by time
};

}  // namespace hapfluid::render
