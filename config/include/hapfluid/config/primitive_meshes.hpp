// Closed primitive meshes generated in code (sphere, box, surface of revolution, cup) for test
// scenes and benchmarks that need bodies without mesh files, and for the renderer's probe ball.
#pragma once

#include <algorithm>
#include <array>
#include <cmath>
#include <map>
#include <utility>
#include <vector>

#include "hapfluid/config/mesh.hpp"

namespace hapfluid::config::primitives {

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
      const double a = 2 * 3.14159265358979323846 * s / segments;
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

}  // namespace hapfluid::config::primitives

namespace hapfluid::sim {
namespace primitives = hapfluid::config::primitives;
}  // namespace hapfluid::sim
