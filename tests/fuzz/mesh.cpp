// Fuzz target: a body mesh file through parse_mesh, as load_mesh reads it for the simulator, the
// renderer and scene validation, then the bounds scene validation takes of it. Built once per
// format (FUZZ_MESH_EXTENSION ".obj" or ".stl"). Bad input must be a ConfigError naming the
// file; an accepted mesh has finite vertices, and triangles whose every index names one of them.
#include <cmath>
#include <string>

#include "config_errors.hpp"
#include "fuzz_target.h"
#include "hapfluid/config/mesh.hpp"

using namespace hapfluid;

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::filesystem::path file = "fuzz/body" FUZZ_MESH_EXTENSION;
  try {
    const config::TriangleMesh mesh =
        config::parse_mesh(std::string(reinterpret_cast<const char*>(data), size), file);
    ++hapfluid_fuzz_accepted;
    if (mesh.triangles.empty()) hapfluid_fuzz_violated("a mesh accepted without triangles");
    for (const config::Vec3& v : mesh.vertices_m)
      if (!std::isfinite(v.x) || !std::isfinite(v.y) || !std::isfinite(v.z))
        hapfluid_fuzz_violated("a mesh accepted with a non-finite vertex");
    for (const auto& triangle : mesh.triangles)
      for (std::uint32_t index : triangle)
        if (index >= mesh.vertices_m.size()) hapfluid_fuzz_violated("a triangle index past the vertices");
    (void)config::mesh_bounds(mesh);
    config::Pose pose;
    pose.orientation = {0.5, 0.5, -0.5, 0.5};
    (void)config::transformed_bounds(mesh, 0.1, pose);
  } catch (const config::ConfigError& error) {
    fuzz::check_config_error(error, file);
  }
  return 0;
}
