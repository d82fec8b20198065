// A small reader for legacy VTK particle files (what `haptic-sim --out` writes and ParaView
// reads): ASCII or BINARY (big-endian), DATASET POLYDATA or UNSTRUCTURED_GRID, file versions
// 2.0-5.1. It keeps the POINTS and every single-component point array (SCALARS or FIELD arrays);
// cells, vectors and cell data are skipped.
#pragma once

#include <filesystem>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include <glm/glm.hpp>

namespace hapfluid::render {

struct VtkPoints {
  std::vector<glm::dvec3> points_m;
  std::map<std::string, std::vector<double>> point_scalars;  // one value per point
  std::optional<double> time_s;                              // a TIME field array, when present
  std::string title;                                         // the file's second line
};

// Throws std::runtime_error("<file>: <where>: <what was wrong>").
VtkPoints read_vtk_points(const std::filesystem::path& file);
VtkPoints parse_vtk_points(const std::string& bytes, const std::string& name_for_messages);

}  // namespace hapfluid::render
