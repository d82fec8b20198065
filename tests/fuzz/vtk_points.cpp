// Fuzz target: a particle frame file through the renderer's legacy VTK reader (haptic-render
// --replay reads whatever *.vtk files it is pointed at). Bad input must be a std::runtime_error
// naming the file; an accepted file has one value per point in every point array.
#include <stdexcept>
#include <string>

#include "fuzz_target.h"
#include "hapfluid/render/vtk_reader.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string name = "fuzz/frame.vtk";
  try {
    const hapfluid::render::VtkPoints points =
        hapfluid::render::parse_vtk_points(std::string(reinterpret_cast<const char*>(data), size), name);
    ++hapfluid_fuzz_accepted;
    for (const auto& [array, values] : points.point_scalars)
      if (values.size() != points.points_m.size()) hapfluid_fuzz_violated("a point array of another length");
  } catch (const std::runtime_error& error) {
    if (std::string(error.what()).rfind(name + ": ", 0) != 0) hapfluid_fuzz_violated("a VTK error that does not name its file");
  }
  return 0;
}
