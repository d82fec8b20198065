#include "hapfluid/sim/mesh_sampling.hpp"

#include <algorithm>
#include <cmath>
#include <map>
#include <stdexcept>
#include <unordered_map>
#include <utility>

namespace hapfluid::sim {

std::vector<Vec3> scaled_vertices(const config::TriangleMesh& mesh, double scale) {
  std::vector<Vec3> out;
  out.reserve(mesh.vertices_m.size());
  for (const auto& v : mesh.vertices_m) out.push_back(Vec3{v.x, v.y, v.z} * scale);
  return out;
}

void check_closed_mesh(const config::TriangleMesh& mesh, const std::string& what) {
  // Each directed edge must appear once and its reverse once: closed (watertight) and
  // consistently oriented, which the divergence theorem and the inside test need.
  std::map<std::pair<std::uint32_t, std::uint32_t>, int> directed;
  for (const auto& t : mesh.triangles)
    for (int e = 0; e < 3; ++e) ++directed[{t[e], t[(e + 1) % 3]}];
  for (const auto& [edge, count] : directed) {
    auto reverse = directed.find({edge.second, edge.first});
    const int back = reverse == directed.end() ? 0 : reverse->second;
    if (count != 1 || back != 1)
      throw std::runtime_error(what + ": mesh is not closed and consistently oriented: edge between vertices " +
                               std::to_string(edge.first + 1) + " and " + std::to_string(edge.second + 1) + " is used " +
                               std::to_string(count) + " time(s) in that direction and " + std::to_string(back) +
                               " time(s) reversed (each edge must be shared by exactly two triangles)");
  }
  if (mass_properties(mesh, 1.0).volume_m3 <= 0)
    throw std::runtime_error(what + ": mesh encloses a negative volume: its triangles must be counter-clockwise seen "
                                    "from outside (flip the face winding)");
}

MassProperties mass_properties(const config::TriangleMesh& mesh, double scale) {
  const std::vector<Vec3> v = scaled_vertices(mesh, scale);
  // Integrals of 1, x, y, z, x^2, y^2, z^2, xy, yz, zx over the volume.
  double in[10] = {0, 0, 0, 0, 0, 0, 0, 0, 0, 0};
  auto subexpressions = [](double w0, double w1, double w2, double& f1, double& f2, double& f3, double& g0, double& g1,
                           double& g2) {
    const double t0 = w0 + w1, t1 = w0 * w0, t2 = t1 + w1 * t0;
    f1 = t0 + w2;
    f2 = t2 + w2 * f1;
    f3 = w0 * t1 + w1 * t2 + w2 * f2;
    g0 = f2 + w0 * (f1 + w0);
    g1 = f2 + w1 * (f1 + w1);
    g2 = f2 + w2 * (f1 + w2);
  };
  for (const auto& t : mesh.triangles) {
    const Vec3 &p0 = v[t[0]], &p1 = v[t[1]], &p2 = v[t[2]];
    const Vec3 d = cross(p1 - p0, p2 - p0);
    double f1x, f2x, f3x, g0x, g1x, g2x, f1y, f2y, f3y, g0y, g1y, g2y, f1z, f2z, f3z, g0z, g1z, g2z;
    subexpressions(p0.x, p1.x, p2.x, f1x, f2x, f3x, g0x, g1x, g2x);
    subexpressions(p0.y, p1.y, p2.y, f1y, f2y, f3y, g0y, g1y, g2y);
    subexpressions(p0.z, p1.z, p2.z, f1z, f2z, f3z, g0z, g1z, g2z);
    in[0] += d.x * f1x;
    in[1] += d.x * f2x;
    in[2] += d.y * f2y;
    in[3] += d.z * f2z;
    in[4] += d.x * f3x;
    in[5] += d.y * f3y;
    in[6] += d.z * f3z;
    in[7] += d.x * (p0.y * g0x + p1.y * g1x + p2.y * g2x);
    in[8] += d.y * (p0.z * g0y + p1.z * g1y + p2.z * g2y);
    in[9] += d.z * (p0.x * g0z + p1.x * g1z + p2.x * g2z);
  }
  const double mult[10] = {1. / 6, 1. / 24, 1. / 24, 1. / 24, 1. / 60, 1. / 60, 1. / 60, 1. / 120, 1. / 120, 1. / 120};
  for (int i = 0; i < 10; ++i) in[i] *= mult[i];
  MassProperties mp;
  mp.volume_m3 = in[0];
  if (std::abs(in[0]) < 1e-300) return mp;
  const Vec3 c{in[1] / in[0], in[2] / in[0], in[3] / in[0]};
  mp.centre_of_mass_m = c;
  Mat3& I = mp.inertia_per_density;
  const double V = in[0];
  I.m[0][0] = in[5] + in[6] - V * (c.y * c.y + c.z * c.z);
  I.m[1][1] = in[4] + in[6] - V * (c.z * c.z + c.x * c.x);
  I.m[2][2] = in[4] + in[5] - V * (c.x * c.x + c.y * c.y);
  I.m[0][1] = I.m[1][0] = -(in[7] - V * c.x * c.y);
  I.m[1][2] = I.m[2][1] = -(in[8] - V * c.y * c.z);
  I.m[0][2] = I.m[2][0] = -(in[9] - V * c.z * c.x);
  return mp;
}

namespace {

struct CellKey {
  long long x, y, z;
  bool operator==(const CellKey& o) const { return x == o.x && y == o.y && z == o.z; }
};
struct CellHash {
  std::size_t operator()(const CellKey& k) const {
    return static_cast<std::size_t>(k.x * 73856093LL ^ k.y * 19349663LL ^ k.z * 83492791LL);
  }
};

}  // namespace

std::vector<Vec3> sample_surface(const config::TriangleMesh& mesh, double scale, double spacing_m, double inset_m) {
  const std::vector<Vec3> v = scaled_vertices(mesh, scale);
  // Outward unit normals: per face, and area-weighted per vertex.
  std::vector<Vec3> vertex_normal(v.size());
  std::vector<Vec3> face_normal;
  face_normal.reserve(mesh.triangles.size());
  for (const auto& t : mesh.triangles) {
    const Vec3 n = cross(v[t[1]] - v[t[0]], v[t[2]] - v[t[0]]);
    for (int c = 0; c < 3; ++c) vertex_normal[t[c]] += n;
    const double len = norm(n);
    face_normal.push_back(len > 0 ? n * (1 / len) : Vec3{});
  }
  for (Vec3& n : vertex_normal) {
    const double len = norm(n);
    if (len > 0) n = n * (1 / len);
  }
  // Candidates: mesh vertices first (corners and rims are kept), then a barycentric lattice on
  // every triangle fine enough (a quarter of the spacing) that thinning leaves no hole. Each is
  // moved inset_m inward along its normal.
  std::vector<Vec3> candidates;
  candidates.reserve(v.size());
  for (std::size_t i = 0; i < v.size(); ++i) candidates.push_back(v[i] - vertex_normal[i] * inset_m);
  const double fine = spacing_m / 4;
  for (std::size_t f = 0; f < mesh.triangles.size(); ++f) {
    const auto& t = mesh.triangles[f];
    const Vec3 &a = v[t[0]], &b = v[t[1]], &c = v[t[2]];
    const double longest = std::max({norm(b - a), norm(c - b), norm(a - c)});
    const int n = std::max(1, static_cast<int>(std::ceil(longest / fine)));
    for (int i = 0; i <= n; ++i)
      for (int j = 0; i + j <= n; ++j) {
        const double u = static_cast<double>(i) / n, w = static_cast<double>(j) / n;
        candidates.push_back(a + (b - a) * u + (c - a) * w - face_normal[f] * inset_m);
      }
  }
  // Greedy thinning: accept a candidate when no accepted sample lies within 0.8 spacing. A
  // maximal set at that radius has about one particle per spacing^2 of surface (a radius of a
  // full spacing leaves only ~0.55 per spacing^2, holes of up to two spacings).
  std::unordered_map<CellKey, std::vector<std::uint32_t>, CellHash> grid;
  std::vector<Vec3> samples;
  const double r_min = kSampleRadiusFactor * spacing_m;
  const double r2 = r_min * r_min * (1 - 1e-9);
  auto key = [&](const Vec3& p) {
    return CellKey{static_cast<long long>(std::floor(p.x / spacing_m)), static_cast<long long>(std::floor(p.y / spacing_m)),
                   static_cast<long long>(std::floor(p.z / spacing_m))};
  };
  for (const Vec3& p : candidates) {
    const CellKey k = key(p);
    bool free = true;
    for (long long dz = -1; dz <= 1 && free; ++dz)
      for (long long dy = -1; dy <= 1 && free; ++dy)
        for (long long dx = -1; dx <= 1 && free; ++dx) {
          auto it = grid.find({k.x + dx, k.y + dy, k.z + dz});
          if (it == grid.end()) continue;
          for (std::uint32_t s : it->second) {
            const Vec3 d = samples[s] - p;
            if (dot(d, d) < r2) {
              free = false;
              break;
            }
          }
        }
    if (!free) continue;
    grid[k].push_back(static_cast<std::uint32_t>(samples.size()));
    samples.push_back(p);
  }
  return samples;
}

int ray_crossings(const std::vector<Vec3>& v, const config::TriangleMesh& mesh, const Vec3& p, const Vec3& dir) {
  int crossings = 0;
  for (const auto& t : mesh.triangles) {
    const Vec3 &a = v[t[0]], &b = v[t[1]], &c = v[t[2]];
    const Vec3 e1 = b - a, e2 = c - a;
    const Vec3 q = cross(dir, e2);
    const double det = dot(e1, q);
    if (std::abs(det) < 1e-18) continue;
    const double inv = 1.0 / det;
    const Vec3 s = p - a;
    const double u = dot(s, q) * inv;
    if (u < 0 || u > 1) continue;
    const Vec3 r = cross(s, e1);
    const double w = dot(dir, r) * inv;
    if (w < 0 || u + w > 1) continue;
    if (dot(e2, r) * inv > 0) ++crossings;
  }
  return crossings;
}

bool inside_closed_mesh(const std::vector<Vec3>& v, const config::TriangleMesh& mesh, const Vec3& p) {
  // Ray along a fixed irrational-ish direction so it almost never grazes an edge or a vertex.
  return (ray_crossings(v, mesh, p, Vec3{0.5773991, 0.5776142, 0.5771396}) & 1) != 0;
}

}  // namespace hapfluid::sim
