// Writes the seed corpus of every fuzz target: small valid inputs, made by the project's own
// writers wherever it has one (the shm channel writers, the loopback link's encoder fed the
// codec's shared test vectors, the shipped rig and scene files, haptic-sim's VTK layout), so
// fuzzing starts from inputs that get past the first checks.
//   fuzz_seeds OUT_DIR        writes OUT_DIR/<target>/<seed>
#include <sys/socket.h>
#include <sys/un.h>
#include <unistd.h>

#include <algorithm>
#include <bit>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <memory>
#include <sstream>
#include <string>
#include <vector>

#include "hapfluid/config/mesh.hpp"
#include "hapfluid/device/loopback.hpp"
#include "hapfluid/device/message_link.hpp"
#include "hapfluid/shm/channel.hpp"
#include "hapfluid/wire/codec.h"
#include "json_mini.hpp"

namespace fs = std::filesystem;
using namespace hapfluid;
using Bytes = std::string;

namespace {

const fs::path kSource = HAPFLUID_SOURCE_DIR;

void write_seed(const fs::path& dir, const std::string& name, const Bytes& bytes) {
  fs::create_directories(dir);
  std::ofstream out(dir / name, std::ios::binary);
  out.write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
  if (!out) throw std::runtime_error("cannot write " + (dir / name).string());
}

Bytes read_file(const fs::path& file) {
  std::ifstream in(file, std::ios::binary);
  if (!in) throw std::runtime_error("cannot read " + file.string());
  std::ostringstream all;
  all << in.rdbuf();
  return all.str();
}

void copy_files(const fs::path& dir, const fs::path& from, const std::string& extension) {
  std::vector<fs::path> files;
  for (const auto& entry : fs::directory_iterator(from))
    if (entry.path().extension() == extension) files.push_back(entry.path());
  std::sort(files.begin(), files.end());
  for (const auto& file : files) write_seed(dir, from.filename().string() + "_" + file.filename().string(), read_file(file));
}

Bytes from_hex(const std::string& hex) {
  const std::vector<unsigned char> bytes = json_mini::hex(hex);
  return Bytes(bytes.begin(), bytes.end());
}

// ---- shm_segment: images of real segments, [u16 n][image at attach][image afterwards] ----------

Bytes segment_image(const std::string& name) { return read_file("/dev/shm" + name); }

Bytes shm_input(const Bytes& at_attach, const Bytes& afterwards) {
  Bytes out;
  out += char(at_attach.size() & 0xFF);
  out += char(at_attach.size() >> 8);
  return out + at_attach + afterwards;
}

void shm_seeds(const fs::path& dir, const std::string& channel, const Bytes& first, const Bytes& second) {
  write_seed(dir, channel + "_attach", shm_input(first, ""));
  write_seed(dir, channel + "_then_published", shm_input(first, second));
  write_seed(dir, channel + "_then_shrunk_to_header", shm_input(first, first.substr(0, sizeof(shm::SegmentHeader))));
  Bytes rewritten = first;
  rewritten[offsetof(shm::SegmentHeader, slot_count)] ^= 1;
  write_seed(dir, channel + "_then_header_rewritten", shm_input(first, rewritten));
}

template <class Record>
void latest_channel_seeds(const fs::path& dir, shm::ChannelKind kind, std::uint64_t payload_bytes, Record first,
                          Record second) {
  const std::string name = "/hapfluid-fuzz-seeds-" + std::to_string(::getpid()) + "." + shm::channel_name(kind);
  shm::LatestWriter writer = shm::LatestWriter::create(name, kind, payload_bytes, 2);
  writer.publish(&first, sizeof first);
  const Bytes a = segment_image(writer.segment().name());
  writer.publish(&second, sizeof second);
  const Bytes b = segment_image(writer.segment().name());
  writer.close();
  shm_seeds(dir, shm::channel_name(kind), a, b);
}

void shm_segment_seeds(const fs::path& dir) {
  shm::DeviceStatesRecord devices{};
  devices.tick = 1;
  devices.device_count = 2;
  for (int i = 0; i < 2; ++i) {
    std::snprintf(devices.devices[i].name, sizeof devices.devices[i].name, "arm%d", i);
    devices.devices[i].present = 1;
    devices.devices[i].orientation[0] = 1;
    devices.devices[i].force_n[0] = 0.5 * i;
  }
  shm::DeviceStatesRecord devices_later = devices;
  devices_later.tick = 2;
  latest_channel_seeds(dir, shm::ChannelKind::device_states, sizeof devices, devices, devices_later);

  shm::SimSample sample{};
  sample.sequence = 1;
  sample.sim_time_s = 0.001;
  sample.body_count = 1;
  sample.device_count = 1;
  sample.bodies[0].orientation[0] = 1;
  sample.couplings[0].valid = 1;
  sample.couplings[0].q0[0] = 1;
  sample.couplings[0].stiffness_n_per_m = 200;
  shm::SimSample sample_later = sample;
  sample_later.sequence = 2;
  latest_channel_seeds(dir, shm::ChannelKind::sim_samples, sizeof sample, sample, sample_later);

  // A particle frame of 4 particles (the writer picks the capacity; readers learn it).
  struct Frame {
    shm::ParticleFrameHeader header;
    shm::ParticleRecord particles[4];
  } frame{};
  static_assert(sizeof(Frame) == shm::particle_frame_bytes(4));
  frame.header.sequence = 1;
  frame.header.particle_count = 3;
  frame.header.max_particles = 4;
  frame.header.body_count = 1;
  frame.header.particle_radius_m = 0.01f;
  frame.header.bodies[0].orientation[0] = 1;
  for (int i = 0; i < 3; ++i) frame.particles[i] = {{0.01f * i, 0.02f, 0.03f}, 0.5f};
  Frame frame_later = frame;
  frame_later.header.sequence = 2;
  frame_later.header.particle_count = 4;
  latest_channel_seeds(dir, shm::ChannelKind::particles, sizeof frame, frame, frame_later);

  const std::string name = "/hapfluid-fuzz-seeds-" + std::to_string(::getpid()) + ".trace";
  shm::RingWriter ring = shm::RingWriter::create(name, shm::ChannelKind::trace, sizeof(shm::TraceRecord), 8);
  shm::TraceRecord record{};
  record.device_count = 1;
  for (int tick = 1; tick <= 3; ++tick) {
    record.tick = tick;
    record.scheduled_ns = 1'000'000ull * tick;
    record.wake_ns = record.scheduled_ns + 20'000;
    ring.push(record);
  }
  const Bytes a = segment_image(ring.segment().name());
  for (int tick = 4; tick <= 12; ++tick) {  // laps the 8 records: a reader loses the oldest
    record.tick = tick;
    ring.push(record);
  }
  const Bytes b = segment_image(ring.segment().name());
  ring.close();
  shm_seeds(dir, "trace", a, b);
}

// ---- meshes --------------------------------------------------------------------------------------

void mesh_seeds(const fs::path& obj_dir, const fs::path& stl_dir) {
  write_seed(obj_dir, "cube.obj", read_file(kSource / "render/docs/cube.obj"));
  write_seed(obj_dir, "slab.obj", read_file(kSource / "config/meshes/slab.obj"));
  // What other exporters write: comments, normals and texture coordinates, quads, n-gons,
  // "v/vt/vn" corners and negative (relative) indices.
  write_seed(obj_dir, "exporter.obj",
             "# exported\nmtllib a.mtl\no prism\nv 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nv 1 0 1\nv 0 1 1\n"
             "vt 0 0\nvn 0 0 1\ns off\nf 1/1/1 3/1/1 2/1/1\nf -3//1 -2//1 -1//1\nf 1 2 5 4\nf 2 3 6 5\n"
             "f 3 1 4 6\n");
  const config::TriangleMesh cube = config::load_mesh(kSource / "render/docs/cube.obj");
  Bytes binary(80, '\0');
  binary.replace(0, 10, "hapfluid  ");
  const auto count = static_cast<std::uint32_t>(cube.triangles.size());
  binary.append(reinterpret_cast<const char*>(&count), 4);
  std::ostringstream ascii;
  ascii << "solid cube\n";
  for (const auto& t : cube.triangles) {
    binary.append(12, '\0');  // facet normal: readers recompute it
    ascii << " facet normal 0 0 0\n  outer loop\n";
    for (std::uint32_t i : t) {
      const config::Vec3& v = cube.vertices_m[i];
      const float xyz[3] = {float(v.x), float(v.y), float(v.z)};
      binary.append(reinterpret_cast<const char*>(xyz), sizeof xyz);
      ascii << "   vertex " << v.x << ' ' << v.y << ' ' << v.z << '\n';
    }
    binary.append(2, '\0');
    ascii << "  endloop\n endfacet\n";
  }
  ascii << "endsolid cube\n";
  write_seed(stl_dir, "cube_binary.stl", binary);
  write_seed(stl_dir, "cube_ascii.stl", ascii.str());
}

// ---- VTK -----------------------------------------------------------------------------------------

template <class T>
void put_big_endian(Bytes& out, T value) {
  char bytes[sizeof(T)];
  std::memcpy(bytes, &value, sizeof(T));
  std::reverse(bytes, bytes + sizeof(T));
  out.append(bytes, sizeof(T));
}

void vtk_seeds(const fs::path& dir) {
  // haptic-sim's own layout (sim_gpu/src/outputs.cpp, write_vtk_frame), 3 particles.
  Bytes sim = "# vtk DataFile Version 3.0\nhapfluid fuzz t=0.5 s\nBINARY\nDATASET POLYDATA\nPOINTS 3 float\n";
  for (int i = 0; i < 9; ++i) put_big_endian(sim, 0.01f * float(i));
  sim += "\nVERTICES 3 6\n";
  for (std::int32_t i = 0; i < 3; ++i) put_big_endian(sim, std::int32_t{1}), put_big_endian(sim, i);
  sim += "\nPOINT_DATA 3\nVECTORS velocity float\n";
  for (int i = 0; i < 9; ++i) put_big_endian(sim, 0.1f);
  for (const char* name : {"density", "pressure"}) {
    sim += std::string("\nSCALARS ") + name + " float 1\nLOOKUP_TABLE default\n";
    for (int i = 0; i < 3; ++i) put_big_endian(sim, 1000.0f);
  }
  for (const char* name : {"kind", "body", "id"}) {
    sim += std::string("\nSCALARS ") + name + " int 1\nLOOKUP_TABLE default\n";
    for (std::int32_t i = 0; i < 3; ++i) put_big_endian(sim, i);
  }
  sim += "\n";
  write_seed(dir, "haptic_sim_binary.vtk", sim);

  write_seed(dir, "ascii_polydata.vtk",
             "# vtk DataFile Version 3.0\nhaptic-sim frame\nASCII\nDATASET POLYDATA\n"
             "FIELD FieldData 1\nTIME 1 1 double\n0.25\n"
             "POINTS 3 float\n0 0 0  0.1 0.2 0.3\n-1.5 2e-3 7\n"
             "VERTICES 3 6\n1 0\n1 1\n1 2\n"
             "POINT_DATA 3\nSCALARS kind int 1\nLOOKUP_TABLE default\n0 1 2\n"
             "VECTORS velocity float\n0 0 0 1 1 1 2 2 2\n");

  // What ParaView writes: an unstructured grid with FIELD point arrays, and VTK 5.1's cells.
  Bytes grid = "# vtk DataFile Version 2.0\nparaview\nBINARY\nDATASET UNSTRUCTURED_GRID\nPOINTS 2 double\n";
  for (double c : {1.0, 2.0, 3.0, -4.0, 5.5, 6.25}) put_big_endian(grid, c);
  grid += "\nCELLS 2 4\n";
  for (std::int32_t c : {1, 0, 1, 1}) put_big_endian(grid, c);
  grid += "\nCELL_TYPES 2\n";
  for (std::int32_t c : {1, 1}) put_big_endian(grid, c);
  grid += "\nPOINT_DATA 2\nFIELD FieldData 2\nspeed 1 2 float\n";
  for (float v : {0.5f, 1.5f}) put_big_endian(grid, v);
  grid += "\nid 1 2 vtktypeint64\n";
  for (std::int64_t v : {7, 8}) put_big_endian(grid, v);
  grid += "\n";
  write_seed(dir, "paraview_unstructured_grid.vtk", grid);

  write_seed(dir, "vtk51_offsets_metadata.vtk",
             "# vtk DataFile Version 5.1\nvtk output\nASCII\nDATASET POLYDATA\n"
             "POINTS 2 float\n0 0 0 1 1 1\nMETADATA\nINFORMATION 0\n\n"
             "VERTICES 3 2\nOFFSETS vtktypeint64\n0 1 2\nCONNECTIVITY vtktypeint64\n0 1\n"
             "POINT_DATA 2\nSCALARS pressure double\nLOOKUP_TABLE default\n1.5 2.5\n");
}

// ---- the wire: the codec's shared test vectors ---------------------------------------------------

void wire_seeds(const fs::path& out, const json_mini::Value& vectors) {
  for (const auto& v : vectors["valid"].items) {
    const std::string name = v["name"].str;
    write_seed(out / "wire_packet", name, from_hex(v["packet"].str));
    const auto id = static_cast<std::uint32_t>(v["canfd"]["id"].num);
    Bytes canfd;
    canfd += char(id & 0xFF);
    canfd += char(id >> 8);
    canfd += char(static_cast<int>(v["node"].num));
    write_seed(out / "wire_canfd", name, canfd + from_hex(v["canfd"]["data"].str));
    if (v["node"].num != 3) continue;  // the can target's assembler is node 3's
    Bytes can;
    for (const auto& frame : v["can"].items) {
      const auto frame_id = static_cast<std::uint32_t>(frame["id"].num);
      const Bytes data = from_hex(frame["data"].str);
      can += char(frame_id & 0xFF);
      can += char(frame_id >> 8);
      can += char(data.size());
      can += data + Bytes(8 - data.size(), '\0');
    }
    write_seed(out / "wire_can", name, can);
  }
}

// ---- haptic arm: the device side of a real loopback link, captured as datagrams ------------------

// Operations of the haptic_arm target (haptic_arm.cpp).
constexpr char kOpDatagram = 0, kOpPoll = 1, kOpTick = 3;

class DeviceSide {
 public:
  explicit DeviceSide(device::Framing framing)
      : path_("/tmp/hapfluid-fuzz-seeds-" + std::to_string(::getpid()) + "-" + device::to_string(framing) + ".sock") {
    const auto format = framing == device::Framing::hid    ? device::LoopbackFormat::hid
                        : framing == device::Framing::bulk ? device::LoopbackFormat::bulk
                                                           : device::LoopbackFormat::can;
    link_ = std::make_unique<device::MessageLink>(
        std::make_unique<device::LoopbackTransport>(path_, device::LoopbackRole::bus, format), framing, 3,
        device::Side::device);
    host_ = ::socket(AF_UNIX, SOCK_SEQPACKET | SOCK_CLOEXEC, 0);
    sockaddr_un address{};
    address.sun_family = AF_UNIX;
    std::snprintf(address.sun_path, sizeof address.sun_path, "%s", path_.c_str());
    if (::connect(host_, reinterpret_cast<const sockaddr*>(&address), sizeof address) != 0)
      throw std::runtime_error("cannot connect to " + path_);
  }
  ~DeviceSide() { ::close(host_); }
  // The operations that deliver `m` to the host exactly as the link puts it on the wire.
  Bytes datagrams(const hf_message& m) {
    if (!link_->send(m)) throw std::runtime_error("the device link refused a test vector");
    Bytes ops;
    char unit[256];
    for (ssize_t n; (n = ::recv(host_, unit, sizeof unit, MSG_DONTWAIT)) > 0;) {
      ops += kOpDatagram;
      ops += char(n);
      ops.append(unit, static_cast<std::size_t>(n));
    }
    return ops;
  }

 private:
  std::string path_;
  std::unique_ptr<device::MessageLink> link_;
  int host_ = -1;
};

hf_message decoded(const json_mini::Value& vector) {
  const Bytes packet = from_hex(vector["packet"].str);
  hf_message m;
  if (hf_decode_packet(reinterpret_cast<const std::uint8_t*>(packet.data()), packet.size(), &m) != HF_OK)
    throw std::runtime_error("test vector " + vector["name"].str + " does not decode");
  return m;
}

const json_mini::Value& vector_named(const json_mini::Value& vectors, const std::string& name) {
  for (const auto& v : vectors["valid"].items)
    if (v["name"].str == name) return v;
  throw std::runtime_error("no test vector " + name);
}

void arm_seeds(const fs::path& dir, device::Framing framing, const json_mini::Value& vectors) {
  DeviceSide device(framing);
  Bytes every;
  for (const auto& v : vectors["valid"].items) {
    const hf_message m = decoded(v);
    const Bytes ops = device.datagrams(m) + kOpPoll;
    every += ops;
    // Alone, only what the host acts on (device messages, and commands it did not send).
    if (m.type == HF_MSG_STATE || m.type == HF_MSG_INFO || m.type == HF_MSG_FAULT ||
        m.type == HF_MSG_DEVICE_HEARTBEAT || m.type == HF_MSG_COMMAND)
      write_seed(dir, v["name"].str, ops);
  }
  write_seed(dir, "every_vector", every);

  // A session: INFO, then a state per 1 kHz tick echoing the host's commands, a fault on the
  // way, one state lost and one late, then the device restarting its counter.
  hf_message info = decoded(vector_named(vectors, "info"));
  hf_message state = decoded(vector_named(vectors, "state_moving_buttons_status"));
  hf_message fault = decoded(vector_named(vectors, "fault_watchdog"));
  Bytes session = device.datagrams(info);
  for (std::uint16_t tick = 0; tick < 40; ++tick) {
    state.seq = tick < 30 ? tick : static_cast<std::uint16_t>(tick - 30);
    state.body.state.command_echo = static_cast<std::uint8_t>(tick == 0 ? 0 : tick - 1);
    if (tick != 12) session += device.datagrams(state);
    if (tick == 15) session += device.datagrams(state);  // a repeat
    if (tick == 20) session += device.datagrams(fault);
    session += kOpTick;
  }
  write_seed(dir, "session", session + kOpPoll);
}

}  // namespace

int main(int argc, char** argv) {
  if (argc != 2) {
    std::fprintf(stderr, "usage: %s OUT_DIR   (writes OUT_DIR/<target>/<seed> for every fuzz target)\n", argv[0]);
    return 2;
  }
  const fs::path out = argv[1];
  try {
    // Rewritten whole, so no seed of an older version lingers.
    for (const char* target : {"shm_segment", "config_rig", "config_scene", "mesh_obj", "mesh_stl", "vtk_points",
                               "wire_packet", "wire_canfd", "wire_can", "arm_can", "arm_canfd", "arm_hid", "arm_bulk"})
      fs::remove_all(out / target);
    const json_mini::Value vectors = json_mini::load((kSource / "firmware_bridge/test_vectors/vectors.json").string());
    shm_segment_seeds(out / "shm_segment");
    copy_files(out / "config_rig", kSource / "config/rigs", ".toml");
    copy_files(out / "config_rig", kSource / "tests/rt_core/rigs", ".toml");
    copy_files(out / "config_scene", kSource / "config/scenes", ".toml");
    mesh_seeds(out / "mesh_obj", out / "mesh_stl");
    vtk_seeds(out / "vtk_points");
    wire_seeds(out, vectors);
    for (auto framing : {device::Framing::can, device::Framing::canfd, device::Framing::hid, device::Framing::bulk})
      arm_seeds(out / (std::string("arm_") + device::to_string(framing)), framing, vectors);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "fuzz_seeds: %s\n", e.what());
    return 1;
  }
  std::printf("fuzz_seeds: seed corpora written under %s\n", out.c_str());
  return 0;
}
