// Files a user opens after a run: particle frames as legacy VTK (binary, ParaView), body and
// coupling histories as CSV, run statistics as JSON. Every file is written under a temporary
// name and renamed when complete, so a crashed run never leaves a file that looks finished.
#pragma once

#include <cstdio>
#include <filesystem>
#include <string>

#include "hapfluid/config/json_output.hpp"
#include "hapfluid/sim/model.hpp"

namespace hapfluid::sim {

// One frame: every particle (fluid, walls, static and dynamic bodies) with velocity, density,
// pressure, kind (0 fluid, 1 wall, 2 body), body index (-1 for fluid and walls) and id.
void write_vtk_frame(const std::filesystem::path& file, const SimulationModel& model, double time_s);

// One point per body at its centre of mass: velocity, angular velocity, the fluid's and the
// couplings' force and torque (vectors), orientation (w, x, y, z of the mesh frame) and index.
void write_vtk_bodies(const std::filesystem::path& file, const SimulationModel& model, double time_s);

// A run's particle frames: DIR/frame_NNNNNN.vtk every `interval_s` of simulated time (haptic-sim
// --export-every, batch and live alike; 0: none), and DIR/particles.vtk.series, ParaView's file
// series (JSON: each frame's name and simulated time, s), rewritten after every frame so that
// ParaView's time axis is the simulated time even for a run cut short. A scene with bodies gets
// DIR/bodies_NNNNNN.vtk (write_vtk_bodies) and DIR/bodies.vtk.series beside them. The
// constructor creates DIR; an earlier run's frames there are remove_previous_outputs' to remove,
// before.
class VtkFrameSeries {
 public:
  VtkFrameSeries(std::filesystem::path dir, double interval_s);
  bool due(double time_s) const { return interval_s_ > 0 && time_s + 1e-9 >= next_s_; }
  // Writes the next frame of `model` at `time_s` (throws std::runtime_error naming the file).
  void write(const SimulationModel& model, double time_s);
  int written() const { return written_; }

 private:
  std::filesystem::path dir_;
  double interval_s_ = 0, next_s_ = 0;
  int written_ = 0;
  config::Json series_entries_, body_series_entries_;  // each series so far (ParaView .vtk.series)
};

// A CSV file written row by row to "<file>.part" and renamed to <file> by finish().
class CsvFile {
 public:
  CsvFile(std::filesystem::path file, const std::string& header);
  ~CsvFile();
  CsvFile(const CsvFile&) = delete;
  CsvFile& operator=(const CsvFile&) = delete;
  void row(const std::string& line);
  void finish();

 private:
  std::filesystem::path file_, part_;
  std::FILE* out_ = nullptr;
};

// History rows, the same in batch and live runs on every backend. Numbers are "%.9g".
inline constexpr const char* kBodiesCsvHeader = "t,body,px,py,pz,qw,qx,qy,qz,vx,vy,vz,wx,wy,wz,fx,fy,fz,tx,ty,tz";
inline constexpr const char* kCouplingsCsvHeader = "t,device,body,fx,fy,fz,tx,ty,tz";
std::string csv_number(double v);
std::string csv_vec3(const Vec3& v);
// One row per body: pose of the mesh frame, velocities, and the fluid's force and torque on it.
std::string body_row(const RigidBody& body, double time_s);
// One row per coupling: the wrench to render on the device (without a line end).
std::string coupling_row(const SimulationModel& model, const VirtualCoupling& coupling, double time_s);

// Writes text to file atomically (temporary name, then rename).
void write_text_atomically(const std::filesystem::path& file, const std::string& text);

// Removes what a previous run left in the output folder `dir`, stats.json first (from then on
// nothing there claims a complete run), then bodies.csv, couplings.csv (and their .part) and
// the frames in particles/ (*.vtk, *.part). A run calls it once its scene has loaded and built,
// just before it writes: a scene that fails leaves the previous run's outputs untouched.
void remove_previous_outputs(const std::filesystem::path& dir);

}  // namespace hapfluid::sim
