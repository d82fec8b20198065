#include "hapfluid/render/replay_source.hpp"

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <cstdio>
#include <stdexcept>

#include "hapfluid/config/log.hpp"
#include "hapfluid/render/scene_description.hpp"
#include "hapfluid/render/vtk_reader.hpp"

namespace hapfluid::render {
namespace {

// haptic-sim writes "hapfluid <scene> t=<seconds> s" as the VTK title.
std::optional<double> time_from_title(const std::string& title) {
  const size_t at = title.find(" t=");
  if (at == std::string::npos) return std::nullopt;
  const char* start = title.c_str() + at + 3;
  char* end = nullptr;
  const double t = std::strtod(start, &end);
  if (end == start || !std::isfinite(t)) return std::nullopt;
  return t;
}

}  // namespace

ReplaySource::ReplaySource(const std::filesystem::path& run_dir, const config::Scene& scene, std::string kind_field)
    : description_(describe_scene(scene)), kind_field_(std::move(kind_field)), frame_rate_hz_(scene.time.frame_rate_hz) {
  for (const auto& b : scene.bodies) body_names_.push_back(b.name);
  const auto particles = run_dir / "particles";
  std::error_code ec;
  if (!std::filesystem::is_directory(particles, ec))
    throw std::runtime_error(particles.string() + ": no particle frames (expected the output folder of haptic-sim --out)");
  for (const auto& entry : std::filesystem::directory_iterator(particles)) {
    const auto name = entry.path().filename().string();
    if (name.rfind("frame_", 0) == 0 && entry.path().extension() == ".vtk") files_.push_back(entry.path());
  }
  if (files_.empty()) throw std::runtime_error(particles.string() + ": no frame_NNNNNN.vtk files");
  std::sort(files_.begin(), files_.end());
  const auto csv = run_dir / "bodies.csv";
  if (std::filesystem::exists(csv, ec)) bodies_ = BodyHistory::load(csv);
  else if (!body_names_.empty())
    throw std::runtime_error(csv.string() + ": missing, but the scene has bodies to place");
}

FrameStatus ReplaySource::next_frame(Frame& frame) {
  if (next_ >= files_.size()) return FrameStatus::end_of_stream;
  const auto& file = files_[next_];
  VtkPoints vtk = read_vtk_points(file);
  frame.index = next_;
  frame.sim_time_s = vtk.time_s ? *vtk.time_s : time_from_title(vtk.title).value_or(double(next_) / frame_rate_hz_);
  frame.fluid_m.clear();
  frame.solid_m.clear();
  auto kinds = vtk.point_scalars.find(kind_field_);
  if (kinds == vtk.point_scalars.end() && !warned_no_kind_) {
    log::warning("%s: no point array \"%s\"; drawing every point as fluid",
                 file.string().c_str(), kind_field_.c_str());
    warned_no_kind_ = true;
  }
  for (size_t i = 0; i < vtk.points_m.size(); ++i) {
    const glm::vec3 p(vtk.points_m[i]);
    const bool fluid = kinds == vtk.point_scalars.end() || kinds->second[i] == 0.0;
    (fluid ? frame.fluid_m : frame.solid_m).push_back(p);
  }
  frame.body_poses.assign(body_names_.size(), BodyPose{});
  for (size_t b = 0; b < body_names_.size(); ++b) {
    BodyPose pose;
    // The body column holds the body's name (or its index in the scene). A body missing from the
    // history stays at its scene pose (static bodies may not be logged).
    const bool logged = bodies_ && (bodies_->pose_at(body_names_[b], frame.sim_time_s, pose) ||
                                    bodies_->pose_at(std::to_string(b), frame.sim_time_s, pose));
    frame.body_poses[b] = logged ? pose : description_.bodies[b].initial_pose;
  }
  ++next_;
  return FrameStatus::new_frame;
}

}  // namespace hapfluid::render
