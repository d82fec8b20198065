#include "hapfluid/sim/outputs.hpp"

#include <array>
#include <bit>
#include <cerrno>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <stdexcept>
#include <vector>

namespace hapfluid::sim {
namespace {

[[noreturn]] void io_error(const std::string& what, const std::filesystem::path& file) {
  throw std::runtime_error(what + " " + file.string() + ": " + std::strerror(errno));
}

// Legacy VTK binary data is big-endian.
template <class T>
void put_be(std::vector<char>& out, T value) {
  static_assert(sizeof(T) == 4);
  std::uint32_t bits;
  std::memcpy(&bits, &value, 4);
  if constexpr (std::endian::native == std::endian::little) bits = __builtin_bswap32(bits);
  const char* b = reinterpret_cast<const char*>(&bits);
  out.insert(out.end(), b, b + 4);
}

void put_text(std::vector<char>& out, const std::string& text) { out.insert(out.end(), text.begin(), text.end()); }

// The header, points and one vertex cell per point of a legacy binary POLYDATA file.
template <class Pos>
void put_point_cloud(std::vector<char>& out, const std::string& title, std::size_t n, Pos&& position) {
  put_text(out, "# vtk DataFile Version 3.0\n" + title + "\nBINARY\nDATASET POLYDATA\nPOINTS " + std::to_string(n) +
                    " float\n");
  for (std::size_t i = 0; i < n; ++i) {
    const auto p = position(i);
    put_be(out, static_cast<float>(p[0])), put_be(out, static_cast<float>(p[1])), put_be(out, static_cast<float>(p[2]));
  }
  put_text(out, "\nVERTICES " + std::to_string(n) + " " + std::to_string(2 * n) + "\n");
  for (std::size_t i = 0; i < n; ++i) put_be(out, std::int32_t{1}), put_be(out, static_cast<std::int32_t>(i));
  put_text(out, "\nPOINT_DATA " + std::to_string(n));
}

void write_bytes_atomically(const std::filesystem::path& file, const char* bytes, std::size_t size) {
  const std::filesystem::path part = file.string() + ".part";
  {
    std::ofstream s(part, std::ios::binary);
    if (!s) io_error("cannot write", part);
    s.write(bytes, static_cast<std::streamsize>(size));
    if (!s) io_error("write failed for", part);
  }
  std::filesystem::rename(part, file);
}

std::string frame_title(const SimulationModel& m, double time_s) {
  return "hapfluid " + m.scene_name + " t=" + std::to_string(time_s) + " s";
}

}  // namespace

void write_text_atomically(const std::filesystem::path& file, const std::string& text) {
  write_bytes_atomically(file, text.data(), text.size());
}

void remove_previous_outputs(const std::filesystem::path& dir) {
  std::filesystem::remove(dir / "stats.json");
  std::filesystem::remove(dir / "stats.json.part");
  for (const char* csv : {"bodies.csv", "couplings.csv"}) {
    std::filesystem::remove(dir / csv);
    std::filesystem::remove(dir / (std::string(csv) + ".part"));
  }
  const std::filesystem::path frames = dir / "particles";
  if (!std::filesystem::is_directory(frames)) return;
  for (const auto& entry : std::filesystem::directory_iterator(frames))
    if (entry.path().extension() == ".vtk" || entry.path().extension() == ".series" || entry.path().extension() == ".part")
      std::filesystem::remove(entry.path());
}

void write_vtk_frame(const std::filesystem::path& file, const SimulationModel& m, double time_s) {
  const FluidParticles& f = m.fluid;
  const SortedSolids& st = m.static_solids;
  const BodyParticles& bp = m.body_particles;
  const std::size_t n = f.size() + st.size() + bp.size();
  struct Point { float x, y, z, vx, vy, vz, density, pressure; std::int32_t kind, body, id; };
  std::vector<Point> pts;
  pts.reserve(n);
  for (std::size_t i = 0; i < f.size(); ++i)
    pts.push_back({f.x[i], f.y[i], f.z[i], f.vx[i], f.vy[i], f.vz[i], f.density[i], f.pressure[i], 0, -1,
                   static_cast<std::int32_t>(f.id[i])});
  for (std::size_t i = 0; i < st.size(); ++i) {
    const bool wall = st.body[i] == kWall;
    pts.push_back({st.x[i], st.y[i], st.z[i], 0, 0, 0, m.params.rest_density_kg_m3, 0,
                   static_cast<std::int32_t>(wall ? ParticleKind::wall : ParticleKind::body), st.body[i],
                   static_cast<std::int32_t>(st.source[i])});
  }
  for (std::size_t i = 0; i < bp.size(); ++i)
    pts.push_back({bp.x[i], bp.y[i], bp.z[i], bp.vx[i], bp.vy[i], bp.vz[i], m.params.rest_density_kg_m3, bp.pressure[i],
                   static_cast<std::int32_t>(ParticleKind::body), bp.body[i], static_cast<std::int32_t>(i)});

  std::vector<char> out;
  out.reserve(n * 60 + 1024);
  put_point_cloud(out, frame_title(m, time_s), n,
                  [&](std::size_t i) { return std::array<float, 3>{pts[i].x, pts[i].y, pts[i].z}; });
  put_text(out, "\nVECTORS velocity float\n");
  for (const Point& p : pts) put_be(out, p.vx), put_be(out, p.vy), put_be(out, p.vz);
  auto scalars = [&](const char* name, const char* type, auto get) {
    put_text(out, std::string("\nSCALARS ") + name + " " + type + " 1\nLOOKUP_TABLE default\n");
    for (const Point& p : pts) put_be(out, get(p));
  };
  scalars("density", "float", [](const Point& p) { return p.density; });
  scalars("pressure", "float", [](const Point& p) { return p.pressure; });
  scalars("kind", "int", [](const Point& p) { return p.kind; });
  scalars("body", "int", [](const Point& p) { return p.body; });
  scalars("id", "int", [](const Point& p) { return p.id; });
  put_text(out, "\n");
  write_bytes_atomically(file, out.data(), out.size());
}

void write_vtk_bodies(const std::filesystem::path& file, const SimulationModel& m, double time_s) {
  const std::vector<RigidBody>& bodies = m.bodies;
  std::vector<char> out;
  put_point_cloud(out, frame_title(m, time_s), bodies.size(), [&](std::size_t i) {
    const Vec3& p = bodies[i].position;
    return std::array<double, 3>{p.x, p.y, p.z};
  });
  auto vectors = [&](const char* name, auto get) {
    put_text(out, std::string("\nVECTORS ") + name + " float\n");
    for (const RigidBody& b : bodies) {
      const Vec3 v = get(b);
      put_be(out, static_cast<float>(v.x)), put_be(out, static_cast<float>(v.y)), put_be(out, static_cast<float>(v.z));
    }
  };
  vectors("velocity", [](const RigidBody& b) { return b.linear_velocity; });
  vectors("angular_velocity", [](const RigidBody& b) { return b.angular_velocity; });
  vectors("fluid_force", [](const RigidBody& b) { return b.fluid_force; });
  vectors("fluid_torque", [](const RigidBody& b) { return b.fluid_torque; });
  vectors("coupling_force", [](const RigidBody& b) { return b.coupling_force; });
  vectors("coupling_torque", [](const RigidBody& b) { return b.coupling_torque; });
  put_text(out, "\nSCALARS orientation float 4\nLOOKUP_TABLE default\n");
  for (const RigidBody& b : bodies)
    for (double q : {b.orientation.w, b.orientation.x, b.orientation.y, b.orientation.z}) put_be(out, static_cast<float>(q));
  put_text(out, "\nSCALARS body int 1\nLOOKUP_TABLE default\n");
  for (std::size_t i = 0; i < bodies.size(); ++i) put_be(out, static_cast<std::int32_t>(i));
  put_text(out, "\n");
  write_bytes_atomically(file, out.data(), out.size());
}

VtkFrameSeries::VtkFrameSeries(std::filesystem::path dir, double interval_s)
    : dir_(std::move(dir)), interval_s_(interval_s) {
  if (interval_s_ > 0) std::filesystem::create_directories(dir_);
}

void VtkFrameSeries::write(const SimulationModel& model, double time_s) {
  // ParaView's file series: {"file-series-version": "1.0", "files": [{"name", "time"}, ...]}.
  auto add = [&](const char* pattern, config::Json& series_json, const char* series,
                 void (*writer)(const std::filesystem::path&, const SimulationModel&, double)) {
    char name[64];
    std::snprintf(name, sizeof name, pattern, written_);
    writer(dir_ / name, model, time_s);
    if (series_json.is_null()) series_json = {{"file-series-version", "1.0"}, {"files", config::Json::array()}};
    series_json["files"].push_back({{"name", name}, {"time", time_s}});
    write_text_atomically(dir_ / series, config::json_text(series_json));
  };
  add("frame_%06d.vtk", series_entries_, "particles.vtk.series", write_vtk_frame);
  if (!model.bodies.empty()) add("bodies_%06d.vtk", body_series_entries_, "bodies.vtk.series", write_vtk_bodies);
  ++written_;
  // A caller that looks less often than the interval (live: at the frame rate) gets one frame
  // per look, not a burst to catch up.
  next_s_ += interval_s_;
  if (next_s_ <= time_s) next_s_ = time_s + interval_s_;
}

CsvFile::CsvFile(std::filesystem::path file, const std::string& header)
    : file_(std::move(file)), part_(file_.string() + ".part") {
  out_ = std::fopen(part_.c_str(), "w");
  if (!out_) io_error("cannot write", part_);
  row(header);
}

CsvFile::~CsvFile() {
  if (out_) std::fclose(out_);  // left as .part: the run did not finish
}

void CsvFile::row(const std::string& line) {
  if (std::fputs(line.c_str(), out_) < 0 || std::fputc('\n', out_) < 0) io_error("write failed for", part_);
}

void CsvFile::finish() {
  if (std::fclose(out_) != 0) {
    out_ = nullptr;
    io_error("write failed for", part_);
  }
  out_ = nullptr;
  std::filesystem::rename(part_, file_);
}

std::string csv_number(double v) {
  char buf[40];
  std::snprintf(buf, sizeof buf, "%.9g", v);
  return buf;
}

std::string csv_vec3(const Vec3& v) { return csv_number(v.x) + "," + csv_number(v.y) + "," + csv_number(v.z); }

std::string body_row(const RigidBody& b, double t) {
  const config::Pose pose = b.mesh_pose();
  return csv_number(t) + "," + b.name + "," + csv_number(pose.position_m.x) + "," + csv_number(pose.position_m.y) + "," +
         csv_number(pose.position_m.z) + "," + csv_number(pose.orientation.w) + "," + csv_number(pose.orientation.x) + "," +
         csv_number(pose.orientation.y) + "," + csv_number(pose.orientation.z) + "," + csv_vec3(b.linear_velocity) + "," +
         csv_vec3(b.angular_velocity) + "," + csv_vec3(b.fluid_force) + "," + csv_vec3(b.fluid_torque);
}

std::string coupling_row(const SimulationModel& m, const VirtualCoupling& c, double t) {
  return csv_number(t) + "," + m.devices[c.device].name + "," + m.bodies[c.body].name + "," + csv_vec3(c.device_force) +
         "," + csv_vec3(c.device_torque);
}


}  // namespace hapfluid::sim
