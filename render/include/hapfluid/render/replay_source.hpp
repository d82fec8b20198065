// Replays a recorded run of `haptic-sim --out DIR`: DIR/particles/frame_NNNNNN.vtk in index order
// and DIR/bodies.csv for the body poses, with the meshes from the run's scene file.
//
// Particle kinds come from a point scalar (default name "kind"): 0 = fluid, 1 = boundary,
// 2 + k = particle of body k. Without that array every point is drawn as fluid (with a warning).
// A frame's time is its TIME field, else the "t=<s>" haptic-sim puts in the VTK title, else
// index / scene frame rate. bodies.csv names
// a body by its scene name or by its index in the scene's [[bodies]] list.
#pragma once

#include <filesystem>
#include <optional>

#include "hapfluid/config/scene.hpp"
#include "hapfluid/render/bodies_csv.hpp"
#include "hapfluid/render/frame_source.hpp"

namespace hapfluid::render {

class ReplaySource final : public FrameSource {
 public:
  // Throws std::runtime_error naming the folder or file when the run is incomplete.
  ReplaySource(const std::filesystem::path& run_dir, const config::Scene& scene, std::string kind_field = "kind");

  const SceneDescription& scene() const override { return description_; }
  FrameStatus next_frame(Frame& frame) override;
  long frame_count() const override { return long(files_.size()); }

 private:
  SceneDescription description_;
  std::vector<std::string> body_names_;
  std::vector<std::filesystem::path> files_;
  std::optional<BodyHistory> bodies_;
  std::string kind_field_;
  double frame_rate_hz_;
  size_t next_ = 0;
  bool warned_no_kind_ = false;
};

}  // namespace hapfluid::render
