// Triangle meshes for rigid bodies (spoon, bowl, glass, ...): OBJ (v/f, polygons fanned into
// triangles) and STL (ASCII or binary), read into indexed triangles. Used by the simulator to
// sample bodies into particles, by the renderer to draw them, and by validation to check bounds.
#pragma once

#include <array>
#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

#include "hapfluid/config/types.hpp"

namespace hapfluid::config {

struct TriangleMesh {
  std::vector<Vec3> vertices_m;
  std::vector<std::array<std::uint32_t, 3>> triangles;  // counter-clockwise seen from outside
};

// Throws ConfigError naming the file, the line and what was wrong.
TriangleMesh load_mesh(const std::filesystem::path& file);
// The same for a mesh file's bytes; the format comes from file_for_messages' extension.
TriangleMesh parse_mesh(const std::string& bytes, const std::filesystem::path& file_for_messages);

Aabb mesh_bounds(const TriangleMesh& mesh);

// Bounds of the mesh after scaling and placing it at a pose.
Aabb transformed_bounds(const TriangleMesh& mesh, double scale, const Pose& pose);

// Writes an OBJ file (used by the mesh generator and tests). Throws std::runtime_error on I/O errors.
void save_obj(const TriangleMesh& mesh, const std::filesystem::path& file);

}  // namespace hapfluid::config
