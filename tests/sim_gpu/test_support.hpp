// Helpers for the simulator tests: closed test meshes generated in code (sphere, box, cup),
// scenes written to a temporary folder, and a few measurements on a running solver.
#pragma once

#include <array>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <map>
#include <string>
#include <unistd.h>

#include "hapfluid/config/mesh.hpp"
#include "hapfluid/config/scene.hpp"
#include "hapfluid/sim/cpu_solver.hpp"
#include "hapfluid/config/primitive_meshes.hpp"

namespace hapfluid::sim::test {

// Integral over 3D space of a radial function: 4 pi int_0^h r^2 f(r) dr (midpoint rule).
template <class F>
double radial_integral(F f, double h) {
  const int n = 200000;
  double sum = 0;
  for (int i = 0; i < n; ++i) {
    const double r = (i + 0.5) * h / n;
    sum += 4 * kPi * r * r * f(r) * (h / n);
  }
  return sum;
}

inline std::filesystem::path temp_dir(const std::string& name) {
  auto dir = std::filesystem::temp_directory_path() / ("hapfluid_sim_" + name + "_" + std::to_string(getpid()));
  std::filesystem::create_directories(dir);
  return dir;
}

using primitives::sphere_mesh;
using primitives::box_mesh;
using primitives::revolve;
using primitives::cup_mesh;

// Writes a scene (and the meshes it names, relative to it) into dir and loads it.
inline config::Scene write_scene(const std::filesystem::path& dir, const std::string& toml,
                                 const std::map<std::string, config::TriangleMesh>& meshes = {}) {
  for (const auto& [name, mesh] : meshes) config::save_obj(mesh, dir / name);
  const auto file = dir / "scene.toml";
  std::ofstream(file) << toml;
  return config::load_scene(file);
}

inline double fluid_kinetic_energy(const CpuSolver& s) {
  const auto& f = s.model().fluid;
  double e = 0;
  for (std::size_t i = 0; i < f.size(); ++i) e += f.vx[i] * f.vx[i] + f.vy[i] * f.vy[i] + f.vz[i] * f.vz[i];
  return 0.5 * s.params().fluid_particle_mass_kg * e;
}

inline void run_for(Solver& s, double seconds, double frame = 0.01) {
  const int frames = static_cast<int>(std::lround(seconds / frame));
  for (int k = 0; k < frames; ++k) s.advance(frame);
}

}  // namespace hapfluid::sim::test
