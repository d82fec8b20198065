// OBJ and STL readers. Only what rigid bodies need: vertex positions and faces. Normals,
// texture coordinates and materials are ignored; polygons are fanned into triangles.
#include <algorithm>
#include <cmath>
#include <cstring>
#include <fstream>
#include <sstream>

#include "hapfluid/config/errors.hpp"
#include "hapfluid/config/mesh.hpp"

namespace hapfluid::config {
namespace {

[[noreturn]] void fail(const std::filesystem::path& file, int line, const std::string& reason) {
  throw ConfigError({Problem{file.string(), line, "", "", reason}});
}

std::string lower_extension(const std::filesystem::path& file) {
  std::string ext = file.extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char c) { return std::tolower(c); });
  return ext;
}

TriangleMesh load_obj(const std::filesystem::path& file, std::istream& in) {
  TriangleMesh mesh;
  std::string line;
  int number = 0;
  while (std::getline(in, line)) {
    ++number;
    std::istringstream words(line);
    std::string tag;
    if (!(words >> tag) || tag[0] == '#') continue;
    if (tag == "v") {
      Vec3 v;
      if (!(words >> v.x >> v.y >> v.z) || !std::isfinite(v.x) || !std::isfinite(v.y) || !std::isfinite(v.z))
        fail(file, number, "vertex needs 3 finite numbers");
      mesh.vertices_m.push_back(v);
    } else if (tag == "f") {
      std::vector<std::uint32_t> face;
      std::string corner;
      while (words >> corner) {
        long index = std::strtol(corner.c_str(), nullptr, 10);  // "7", "7/1", "7//3"
        if (index < 0) index = static_cast<long>(mesh.vertices_m.size()) + index + 1;
        if (index < 1 || index > static_cast<long>(mesh.vertices_m.size()))
          fail(file, number, "face refers to vertex " + corner + " which is not defined (" +
                                 std::to_string(mesh.vertices_m.size()) + " vertices so far)");
        face.push_back(static_cast<std::uint32_t>(index - 1));
      }
      if (face.size() < 3) fail(file, number, "face needs at least 3 vertices");
      for (size_t i = 1; i + 1 < face.size(); ++i) mesh.triangles.push_back({face[0], face[i], face[i + 1]});
    }
  }
  return mesh;
}

TriangleMesh load_stl_ascii(const std::filesystem::path& file, std::istream& in) {
  TriangleMesh mesh;
  std::string word;
  int corner = 0;
  while (in >> word) {
    if (word != "vertex") continue;
    Vec3 v;
    if (!(in >> v.x >> v.y >> v.z)) fail(file, 0, "ASCII STL vertex needs 3 numbers");
    mesh.vertices_m.push_back(v);
    if (++corner == 3) {
      auto n = static_cast<std::uint32_t>(mesh.vertices_m.size());
      mesh.triangles.push_back({n - 3, n - 2, n - 1});
      corner = 0;
    }
  }
  return mesh;
}

TriangleMesh load_stl_binary(const std::filesystem::path& file, const std::string& bytes) {
  if (bytes.size() < 84) fail(file, 0, "binary STL is shorter than its 84-byte header");
  std::uint32_t count;
  std::memcpy(&count, bytes.data() + 80, 4);
  if (bytes.size() < 84 + 50ull * count)
    fail(file, 0, "binary STL declares " + std::to_string(count) + " triangles but is truncated");
  TriangleMesh mesh;
  for (std::uint32_t t = 0; t < count; ++t) {
    const char* record = bytes.data() + 84 + 50ull * t + 12;  // skip the facet normal
    for (int c = 0; c < 3; ++c) {
      float xyz[3];
      std::memcpy(xyz, record + 12 * c, 12);
      // Raw floats may be NaN or infinite, which no text reader lets through.
      if (!std::isfinite(xyz[0]) || !std::isfinite(xyz[1]) || !std::isfinite(xyz[2]))
        fail(file, 0, "binary STL triangle " + std::to_string(t) + " has a vertex that is not 3 finite numbers");
      mesh.vertices_m.push_back({xyz[0], xyz[1], xyz[2]});
    }
    mesh.triangles.push_back({3 * t, 3 * t + 1, 3 * t + 2});
  }
  return mesh;
}

// STL repeats shared vertices; weld exact duplicates so the mesh is indexed and closed.
void weld(TriangleMesh& mesh) {
  std::vector<std::uint32_t> order(mesh.vertices_m.size());
  for (std::uint32_t i = 0; i < order.size(); ++i) order[i] = i;
  auto key = [&](std::uint32_t i) {
    const Vec3& v = mesh.vertices_m[i];
    return std::tuple(v.x, v.y, v.z);
  };
  std::sort(order.begin(), order.end(), [&](auto a, auto b) { return key(a) < key(b); });
  std::vector<std::uint32_t> remap(order.size());
  std::vector<Vec3> unique;
  for (size_t k = 0; k < order.size(); ++k) {
    if (k == 0 || key(order[k]) != key(order[k - 1])) unique.push_back(mesh.vertices_m[order[k]]);
    remap[order[k]] = static_cast<std::uint32_t>(unique.size() - 1);
  }
  for (auto& t : mesh.triangles)
    for (auto& i : t) i = remap[i];
  mesh.vertices_m = std::move(unique);
}

}  // namespace

TriangleMesh parse_mesh(const std::string& bytes, const std::filesystem::path& file) {
  const std::string ext = lower_extension(file);
  TriangleMesh mesh;
  if (ext == ".obj") {
    std::istringstream text(bytes);
    mesh = load_obj(file, text);
  } else if (ext == ".stl") {
    bool ascii = bytes.rfind("solid", 0) == 0 && bytes.find("facet") != std::string::npos;
    if (ascii) {
      std::istringstream text(bytes);
      mesh = load_stl_ascii(file, text);
    } else {
      mesh = load_stl_binary(file, bytes);
    }
    weld(mesh);
  } else {
    fail(file, 0, "unsupported mesh format \"" + ext + "\": use .obj or .stl");
  }
  if (mesh.triangles.empty()) fail(file, 0, "mesh has no triangles");
  return mesh;
}

TriangleMesh load_mesh(const std::filesystem::path& file) {
  std::ifstream in(file, std::ios::binary);
  if (!in) fail(file, 0, "cannot open mesh file (missing or unreadable)");
  std::ostringstream all;
  all << in.rdbuf();
  return parse_mesh(all.str(), file);
}

Aabb mesh_bounds(const TriangleMesh& mesh) { return transformed_bounds(mesh, 1.0, Pose{}); }

Aabb transformed_bounds(const TriangleMesh& mesh, double scale, const Pose& pose) {
  const Quat& q = pose.orientation;
  // Rotation matrix of q, applied to every scaled vertex.
  const double r[3][3] = {{1 - 2 * (q.y * q.y + q.z * q.z), 2 * (q.x * q.y - q.w * q.z), 2 * (q.x * q.z + q.w * q.y)},
                          {2 * (q.x * q.y + q.w * q.z), 1 - 2 * (q.x * q.x + q.z * q.z), 2 * (q.y * q.z - q.w * q.x)},
                          {2 * (q.x * q.z - q.w * q.y), 2 * (q.y * q.z + q.w * q.x), 1 - 2 * (q.x * q.x + q.y * q.y)}};
  Aabb box{{1e300, 1e300, 1e300}, {-1e300, -1e300, -1e300}};
  for (const Vec3& v : mesh.vertices_m) {
    const double p[3] = {v.x * scale, v.y * scale, v.z * scale};
    double w[3];
    for (int i = 0; i < 3; ++i) w[i] = r[i][0] * p[0] + r[i][1] * p[1] + r[i][2] * p[2];
    const Vec3 x{w[0] + pose.position_m.x, w[1] + pose.position_m.y, w[2] + pose.position_m.z};
    box.min_m = {std::min(box.min_m.x, x.x), std::min(box.min_m.y, x.y), std::min(box.min_m.z, x.z)};
    box.max_m = {std::max(box.max_m.x, x.x), std::max(box.max_m.y, x.y), std::max(box.max_m.z, x.z)};
  }
  return box;
}

void save_obj(const TriangleMesh& mesh, const std::filesystem::path& file) {
  const std::filesystem::path tmp = file.string() + ".tmp";
  {
    std::ofstream out(tmp);
    if (!out) throw std::runtime_error("cannot write " + tmp.string());
    out.precision(9);
    for (const auto& v : mesh.vertices_m) out << "v " << v.x << ' ' << v.y << ' ' << v.z << '\n';
    for (const auto& t : mesh.triangles) out << "f " << t[0] + 1 << ' ' << t[1] + 1 << ' ' << t[2] + 1 << '\n';
    if (!out) throw std::runtime_error("write failed: " + tmp.string());
  }
  std::filesystem::rename(tmp, file);
}

}  // namespace hapfluid::config
