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

namespace hapfluid::sim::test {

inline std::filesystem::path temp_dir(const std::string& name) {
  auto dir = std::filesystem::temp_directory_path() / ("hapfluid_sim_" + name + "_" + std::to_string(getpid()));
  std::filesystem::create_directories(dir);
  return dir;
}

// Icosphere of the given radius centred at the origin (counter-clockwise from outside).
inline config::TriangleMesh sphere_mesh(double radius, int subdivisions) {
  const double t = (1.0 + std::sqrt(5.0)) / 2.0;
  std::vector<config::Vec3> v = {{-1, t, 0}, {1, t, 0}, {-1, -t, 0}, {1, -t, 0}, {0, -1, t}, {0, 1, t},
                                 {0, -1, -t}, {0, 1, -t}, {t, 0, -1}, {t, 0, 1}, {-t, 0, -1}, {-t, 0, 1}};
  std::vector<std::array<std::uint32_t, 3>> f = {{0, 11, 5}, {0, 5, 1},  {0, 1, 7},   {0, 7, 10}, {0, 10, 11},
                                                 {1, 5, 9},  {5, 11, 4}, {11, 10, 2}, {10, 7, 6}, {7, 1, 8},
                                                 {3, 9, 4},  {3, 4, 2},  {3, 2, 6},   {3, 6, 8},  {3, 8, 9},
                                                 {4, 9, 5},  {2, 4, 11}, {6, 2, 10},  {8, 6, 7},  {9, 8, 1}};
  auto unit = [](config::Vec3 p) {
    const double n = std::sqrt(p.x * p.x + p.y * p.y + p.z * p.z);
    return config::Vec3{p.x / n, p.y / n, p.z / n};
  };
  for (auto& p : v) p = unit(p);
  for (int s = 0; s < subdivisions; ++s) {
    std::map<std::pair<std::uint32_t, std::uint32_t>, std::uint32_t> mid;
    auto midpoint = [&](std::uint32_t a, std::uint32_t b) {
      auto key = std::minmax(a, b);
      auto it = mid.find(key);
      if (it != mid.end()) return it->second;
      v.push_back(unit({(v[a].x + v[b].x) / 2, (v[a].y + v[b].y) / 2, (v[a].z + v[b].z) / 2}));
      return mid[key] = static_cast<std::uint32_t>(v.size() - 1);
    };
    std::vector<std::array<std::uint32_t, 3>> next;
    for (auto& tri : f) {
      const std::uint32_t a = midpoint(tri[0], tri[1]), b = midpoint(tri[1], tri[2]), c = midpoint(tri[2], tri[0]);
      next.push_back({tri[0], a, c});
      next.push_back({tri[1], b, a});
      next.push_back({tri[2], c, b});
      next.push_back({a, b, c});
    }
    f = next;
  }
  config::TriangleMesh m;
  for (auto& p : v) m.vertices_m.push_back({p.x * radius, p.y * radius, p.z * radius});
  m.triangles = f;
  return m;
}

// Axis-aligned box [0, size] (corner at the origin).
inline config::TriangleMesh box_mesh(double sx, double sy, double sz) {
  config::TriangleMesh m;
  for (int i = 0; i < 8; ++i) m.vertices_m.push_back({(i & 1) * sx, ((i >> 1) & 1) * sy, ((i >> 2) & 1) * sz});
  m.triangles = {{0, 2, 1}, {1, 2, 3}, {4, 5, 6}, {5, 7, 6}, {0, 1, 4}, {1, 5, 4},
                 {2, 6, 3}, {3, 6, 7}, {0, 4, 2}, {2, 4, 6}, {1, 3, 5}, {3, 7, 5}};
  return m;
}

// Surface of revolution about z of a closed profile (r, z) listed counter-clockwise in the
// (r, z) half-plane; profile points with r = 0 become poles. A cup: open at the top, walls of
// thickness `wall`, bottom at z = 0.
inline config::TriangleMesh revolve(const std::vector<std::pair<double, double>>& profile, int segments) {
  config::TriangleMesh m;
  std::vector<std::vector<std::uint32_t>> ring(profile.size());
  for (std::size_t k = 0; k < profile.size(); ++k) {
    const auto [r, z] = profile[k];
    if (r == 0) {
      m.vertices_m.push_back({0, 0, z});
      ring[k].assign(segments, static_cast<std::uint32_t>(m.vertices_m.size() - 1));
      continue;
    }
    for (int s = 0; s < segments; ++s) {
      const double a = 2 * M_PI * s / segments;
      m.vertices_m.push_back({r * std::cos(a), r * std::sin(a), z});
      ring[k].push_back(static_cast<std::uint32_t>(m.vertices_m.size() - 1));
    }
  }
  for (std::size_t k = 0; k < profile.size(); ++k) {
    const std::size_t n = (k + 1) % profile.size();
    for (int s = 0; s < segments; ++s) {
      const int s1 = (s + 1) % segments;
      const std::uint32_t a = ring[k][s], b = ring[k][s1], c = ring[n][s1], d = ring[n][s];
      if (a != b) m.triangles.push_back({a, b, c});
      if (c != d) m.triangles.push_back({a, c, d});
    }
  }
  return m;
}

inline config::TriangleMesh cup_mesh(double radius, double height, double wall, int segments) {
  // Counter-clockwise in (r, z) seen with r to the right and z up gives outward normals.
  return revolve({{0, 0}, {radius, 0}, {radius, height}, {radius - wall, height}, {radius - wall, wall}, {0, wall}},
                 segments);
}

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

inline void run_for(CpuSolver& s, double seconds, double frame = 0.01) {
  const int frames = static_cast<int>(std::lround(seconds / frame));
  for (int k = 0; k < frames; ++k) s.advance(frame);
}

}  // namespace hapfluid::sim::test
