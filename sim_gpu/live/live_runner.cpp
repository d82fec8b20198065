#include "live_runner.hpp"
#include "thread_choice.hpp"

#include "hapfluid/sim/thread_pool.hpp"

#include <signal.h>
#include <time.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <memory>
#include <optional>
#include <sstream>
#include <string_view>
#include <vector>

#include "hapfluid/config/build_id.hpp"
#include "hapfluid/config/errors.hpp"
#include "hapfluid/config/log.hpp"
#include "hapfluid/config/rig.hpp"
#include "hapfluid/config/scene.hpp"
#include "hapfluid/rt/sd_notify.hpp"
#include "hapfluid/shm/channel.hpp"
#include "hapfluid/sim/outputs.hpp"
#include "hapfluid/sim/run_stats.hpp"
#include "live_backend.hpp"

namespace hapfluid::sim {
namespace {

std::atomic<bool> g_stop{false};
void on_signal(int) { g_stop.store(true); }

std::string num(double v) { return csv_number(v); }

void sleep_until_ns(std::uint64_t t) {
  timespec ts{static_cast<time_t>(t / 1'000'000'000ull), static_cast<long>(t % 1'000'000'000ull)};
  clock_nanosleep(CLOCK_MONOTONIC, TIMER_ABSTIME, &ts, nullptr);  // EINTR: the loop re-checks
}

void put3(const Vec3& v, double out[3]) { out[0] = v.x, out[1] = v.y, out[2] = v.z; }
void put4(const Quat& q, double out[4]) { out[0] = q.w, out[1] = q.x, out[2] = q.y, out[3] = q.z; }

// The scene device a rig device drives (the rule in live_runner.hpp), or -1.
int match_scene_device(const config::Scene& scene, const SimulationModel& model, const std::string& rig_name) {
  for (std::size_t d = 0; d < model.devices.size(); ++d) {
    const config::SceneDevice* sd = scene.find_device(model.devices[d].name);
    if (sd && sd->source == config::DeviceSource::rig && sd->rig_device == rig_name) return static_cast<int>(d);
  }
  for (std::size_t d = 0; d < model.devices.size(); ++d)
    if (model.devices[d].name == rig_name) return static_cast<int>(d);
  return -1;
}

// Rig frame -> scene frame: the scene device's workspace centre is where the rig origin lands.
DeviceState from_entry(const shm::DeviceStateEntry& e, const Vec3& workspace_centre) {
  DeviceState s;
  s.position = Vec3{e.position_m[0], e.position_m[1], e.position_m[2]} + workspace_centre;
  s.orientation = normalized(Quat{e.orientation[0], e.orientation[1], e.orientation[2], e.orientation[3]});
  s.linear_velocity = {e.linear_velocity_m_s[0], e.linear_velocity_m_s[1], e.linear_velocity_m_s[2]};
  s.angular_velocity = {e.angular_velocity_rad_s[0], e.angular_velocity_rad_s[1], e.angular_velocity_rad_s[2]};
  return s;
}

bool finite_entry(const shm::DeviceStateEntry& e) {
  for (double v : e.position_m) if (!std::isfinite(v)) return false;
  for (double v : e.orientation) if (!std::isfinite(v)) return false;
  for (double v : e.linear_velocity_m_s) if (!std::isfinite(v)) return false;
  for (double v : e.angular_velocity_rad_s) if (!std::isfinite(v)) return false;
  const double n = e.orientation[0] * e.orientation[0] + e.orientation[1] * e.orientation[1] +
                   e.orientation[2] * e.orientation[2] + e.orientation[3] * e.orientation[3];
  return n > 0.25 && n < 4;
}

// The device_states channel as the live sim reads it: attach when haptic-rt appears, follow its
// restarts, forget it when it stops. Calls that do syscalls run at most every 0.25 s.
class DeviceInput {
 public:
  explicit DeviceInput(std::string name) : name_(std::move(name)) {}

  // Returns the newest record when it is newer than the last one returned.
  const shm::DeviceStatesRecord* poll(std::uint64_t now) {
    if (now >= next_check_ns_) {
      next_check_ns_ = now + 250'000'000ull;
      if (reader_.valid()) {
        const shm::WriterStatus s = reader_.check_liveness(now, 500'000'000ull);
        if (s != shm::WriterStatus::live) {
          log::Line(log::Level::notice) << "device states " << shm::to_string(s) << " (haptic-rt stopped?): devices hold their last pose";
          reader_ = shm::LatestReader();
          live_ = false;
        }
      }
      if (!reader_.valid()) {
        try {
          reader_ = shm::LatestReader::attach(name_, shm::ChannelKind::device_states, sizeof(shm::DeviceStatesRecord));
          log::Line(log::Level::info) << "attached to " << name_ << " (haptic-rt pid " << reader_.segment().layout().writer_pid << ")";
          last_generation_ = 0;
        } catch (const shm::ShmError& e) {
          if (!attach_error_said_) log::Line(log::Level::warning) << "waiting for haptic-rt: " << e.what();
          attach_error_said_ = true;
        }
      }
    }
    if (!reader_.valid()) return nullptr;
    std::uint64_t generation = 0;
    if (reader_.try_read(record_, &generation) != shm::ReadResult::ok || generation == last_generation_) return nullptr;
    last_generation_ = generation;
    live_ = true;
    return &record_;
  }
  bool live() const { return live_; }

 private:
  std::string name_;
  shm::LatestReader reader_;
  shm::DeviceStatesRecord record_{};
  std::uint64_t last_generation_ = 0, next_check_ns_ = 0;
  bool attach_error_said_ = false, live_ = false;
};

struct Counters {
  std::uint64_t samples = 0, particle_frames = 0, device_records = 0, lag_events = 0;
  std::uint64_t clamped_reported = 0;  // wall clamp events when first reported (0: none yet)
  double dropped_backlog_s = 0, dt_min = 1e300, dt_max = 0, step_wall_max_s = 0, step_wall_total_s = 0;
  int vtk_frames = 0;
  double vtk_write_max_s = 0, vtk_write_total_s = 0;
  std::string vtk_error;
};

std::string clamp_note(std::uint64_t clamped) {
  return clamped > 0 ? ", " + std::to_string(clamped) + " wall clamps" : std::string();
}

StatsJson probe_json(const BackendProbe& p) {
  if (!p.ran) return nullptr;
  return {{"steps", p.steps}, {"simulated_s", p.simulated_s}, {"wall_s", p.wall_s}, {"steps_per_s", p.steps_per_s()},
          {"real_time_factor", p.real_time_factor()}};
}

std::string stats_json(const LiveOptions& o, const LiveBackend& backend, const Counters& c, const ThreadChoice& threads,
                       double wall_s, const std::vector<std::string>& device_map, bool complete,
                       const std::string& error) {
  const LiveSolver& solver = *backend.solver;
  const ComputeDevice device = solver.device();
  const SimulationModel& m = solver.model();
  const double steps = static_cast<double>(solver.steps());
  const double wall = std::max(wall_s, 1e-9);
  StatsJson j;
  j["mode"] = "live";
  j["complete"] = complete;
  if (!error.empty()) j["error"] = error;
  j["build_id"] = config::build_id();
  j["scene"] = o.scene.string();
  j["backend"] = solver.backend();
  j["device"] = {{"name", device.name}, {"type", device.type}, {"driver", device.driver}};
  j["backend_choice"] = {{"requested", backend.requested},
                         {"reason", backend.reason},
                         {"vulkan_probe", probe_json(backend.vulkan_probe)},
                         {"cpu_probe", probe_json(backend.cpu_probe)}};
  j["threads"] = solver.threads();
  // Steps at all worker threads and at one, as the live sim chose them (thread_choice.hpp).
  j["thread_choice"] = {{"chosen", threads.chosen()},
                        {"probes", threads.probes()},
                        {"steps_with_all", threads.steps_with_all()},
                        {"steps_with_one", threads.steps_with_one()}};
  j["particles"] = {{"fluid", m.fluid.size()},
                    {"boundary", m.wall_particle_count},
                    {"static_body", m.static_body_particle_count},
                    {"body", m.body_particles.size()}};
  j["fluid_mass_kg"] = static_cast<double>(m.fluid.size()) * m.params.fluid_particle_mass_kg;
  j["solver"] = solver.method();
  j["steps"] = solver.steps();
  j["clamped_particle_events"] = solver.clamped_particle_count();
  j["dt_s"] = {{"min", c.dt_min < 1e300 ? c.dt_min : 0.0},
               {"max", c.dt_max},
               {"mean", steps > 0 ? solver.time_s() / steps : 0.0}};
  j["simulated_time_s"] = solver.time_s();
  j["wall_time_s"] = wall_s;
  j["steps_per_s"] = steps / wall;
  j["real_time_factor"] = solver.time_s() / wall;
  j["kept_up_with_wall_clock"] = c.lag_events == 0;
  j["dropped_backlog_s"] = c.dropped_backlog_s;
  j["longest_step_wall_s"] = c.step_wall_max_s;
  // The share of the wall clock the steps took: the sim's headroom is what is left of 1.
  j["step_load"] = c.step_wall_total_s / wall;
  add_solver_work(j, solver);
  j["sim_samples_published"] = c.samples;
  j["particle_frames_published"] = c.particle_frames;
  j["vtk_export_every_s"] = o.export_every_s;
  j["vtk_frames_written"] = c.vtk_frames;
  j["longest_vtk_write_s"] = c.vtk_write_max_s;
  j["vtk_write_total_s"] = c.vtk_write_total_s;
  if (!c.vtk_error.empty()) j["vtk_export_error"] = c.vtk_error;
  j["device_records_read"] = c.device_records;
  j["device_matches"] = device_map;
  return config::json_text(j);
}

}  // namespace

int run_live(const LiveOptions& o) {
  if (o.threads < 1 || o.threads > kMaxWorkerThreads) {
    log::Line(log::Level::error) << "--threads " << o.threads << ": must be 1.." << kMaxWorkerThreads;
    return 2;
  }
  if (o.export_every_s > 0 && o.out.empty()) {
    log::Line(log::Level::error) << "--export-every " << o.export_every_s << ": needs --out DIR (frames go to DIR/particles/)";
    return 2;
  }
  std::string prefix = o.shm_prefix, group;
  config::Scene scene;
  try {
    if (!o.rig.empty()) {
      const config::Rig rig = config::load_rig(o.rig);
      if (prefix.empty()) prefix = rig.rt.shm.prefix;
      group = rig.rt.shm.group;
    }
    scene = config::load_scene(o.scene);
  } catch (const config::ConfigError& e) {
    log::Line line(log::Level::error);
    line << "invalid configuration:";
    for (const auto& p : e.problems()) line << "\n  " << p.to_string();
    return 2;
  }
  if (prefix.empty()) prefix = "hapfluid";

  // Before any segment exists: haptic-rt sees no sim until it is ready (the auto probe takes ~1 s).
  LiveBackend backend;
  try {
    LiveBackendOptions bo;
    bo.backend = o.backend;
    bo.vulkan_device = o.vulkan_device;
    bo.threads = o.threads;
    backend = choose_live_backend(scene, bo);
  } catch (const std::exception& e) {
    log::Line(log::Level::error) << "" << e.what();
    return 2;
  }
  LiveSolver* solver = backend.solver.get();
  const SimulationModel& m = solver->model();
  const std::size_t fluid_count = m.fluid.size();
  if (m.bodies.size() > std::size_t(shm::kMaxBodies))
    log::Line(log::Level::notice) << "note: the scene has " << m.bodies.size() << " bodies; sim_samples and particle frames carry the first "
                                  << shm::kMaxBodies;

  shm::WriterOptions wo;
  wo.group = group;
  shm::LatestWriter samples_writer, particles_writer;
  try {
    samples_writer = shm::LatestWriter::create(shm::segment_name(prefix, shm::ChannelKind::sim_samples),
                                               shm::ChannelKind::sim_samples, sizeof(shm::SimSample), 4, wo);
    particles_writer = shm::LatestWriter::create(shm::segment_name(prefix, shm::ChannelKind::particles),
                                                 shm::ChannelKind::particles,
                                                 shm::particle_frame_bytes(static_cast<std::uint32_t>(fluid_count)), 3, wo);
  } catch (const shm::ShmError& e) {
    log::Line(log::Level::error) << "" << e.what();
    return 2;
  }

  struct sigaction action {};
  action.sa_handler = on_signal;
  sigaction(SIGINT, &action, nullptr);
  sigaction(SIGTERM, &action, nullptr);

  std::optional<CsvFile> couplings_csv, bodies_csv;
  std::optional<VtkFrameSeries> vtk_frames;
  try {
    if (!o.out.empty()) {
      std::filesystem::create_directories(o.out);
      remove_previous_outputs(o.out);  // no earlier run's stats.json, CSVs or frames pass for this run's
      couplings_csv.emplace(o.out / "couplings.csv", "t,device,body,fx,fy,fz,tx,ty,tz,wall_s,device_tick,publish_ns");
      bodies_csv.emplace(o.out / "bodies.csv", kBodiesCsvHeader);
      if (o.export_every_s > 0) vtk_frames.emplace(o.out / "particles", o.export_every_s);
    }
  } catch (const std::exception& e) {
    log::Line(log::Level::error) << "--out " << o.out.string() << ": " << e.what();
    return 2;
  }

  const ComputeDevice device = solver->device();
  log::Line(log::Level::info) << "live: backend " << solver->backend() << " on " << device.name
                              << (device.driver.empty() ? "" : " (" + device.type + ", " + device.driver + ")") << " [" << backend.reason
                              << "]; scene \"" << m.scene_name << "\", " << fluid_count << " fluid particles, " << m.bodies.size()
                              << " bodies, " << m.devices.size() << " scene devices; shm /" << prefix
                              << ".{sim_samples,particles} (reads /" << prefix << ".device_states)";

  // Buffers reused every step: nothing below allocates per step except the CSV rows.
  auto sample = std::make_unique<shm::SimSample>();
  std::snprintf(sample->backend, sizeof sample->backend, "%s", solver->backend());
  sample->fluid_particles = static_cast<std::uint32_t>(fluid_count);
  const bool cpu_backend = std::string_view(solver->backend()) == "cpu";
  std::vector<std::byte> frame(shm::particle_frame_bytes(static_cast<std::uint32_t>(fluid_count)));
  std::vector<int> live_device_of_scene(m.devices.size(), -1);  // device_states index driving each scene device
  std::vector<int> scene_device_of_entry(shm::kMaxDevices, -1);
  std::vector<std::string> device_map(shm::kMaxDevices);
  std::vector<bool> unmatched_said(shm::kMaxDevices, false);
  std::vector<DeviceState> held(m.devices.size());
  std::vector<Vec3> centre(m.devices.size());
  for (std::size_t d = 0; d < m.devices.size(); ++d)
    if (const config::SceneDevice* sd = scene.find_device(m.devices[d].name)) centre[d] = from_config(sd->workspace_centre_m);
  for (std::size_t d = 0; d < m.devices.size(); ++d) held[d] = device_state_from(config::evaluate_motion(m.devices[d].motion, 0));
  shm::DeviceStatesRecord devices{};
  bool have_devices = false;
  DeviceInput input(shm::segment_name(prefix, shm::ChannelKind::device_states));

  rt::SdNotifier notifier;
  notifier.send("READY=1");
  const std::uint64_t watchdog_ns = notifier.watchdog_ping_interval_ns();

  Counters c;
  ThreadChoice thread_choice(solver->threads());
  const std::uint64_t start_ns = shm::monotonic_ns();
  std::uint64_t origin_ns = start_ns;  // wall time of simulated time 0 (moves when the backlog is dropped)
  const double frame_period = 1.0 / m.params.frame_rate_hz;
  double next_frame_s = 0, next_body_row_s = 0;
  std::uint64_t next_status_ns = start_ns + static_cast<std::uint64_t>(o.status_every_s * 1e9);
  std::uint64_t next_watchdog_ns = start_ns, status_steps = 0;
  double status_sim_s = 0;
  std::uint64_t status_wall_ns = start_ns;
  std::string error;

  auto publish_particles = [&](std::uint64_t now) {
    shm::ParticleFrameHeader h{};
    h.sequence = solver->steps();
    h.sim_time_s = solver->time_s();
    h.publish_ns = now;
    h.particle_count = static_cast<std::uint32_t>(fluid_count);
    h.max_particles = static_cast<std::uint32_t>(fluid_count);
    h.body_count = static_cast<std::uint32_t>(std::min<std::size_t>(m.bodies.size(), shm::kMaxBodies));
    h.particle_radius_m = 0.5f * m.params.particle_spacing_m;
    for (std::uint32_t b = 0; b < h.body_count; ++b) {
      const config::Pose p = m.bodies[b].mesh_pose();
      h.bodies[b].position_m[0] = p.position_m.x, h.bodies[b].position_m[1] = p.position_m.y;
      h.bodies[b].position_m[2] = p.position_m.z;
      h.bodies[b].orientation[0] = p.orientation.w, h.bodies[b].orientation[1] = p.orientation.x;
      h.bodies[b].orientation[2] = p.orientation.y, h.bodies[b].orientation[3] = p.orientation.z;
    }
    std::memcpy(frame.data(), &h, sizeof h);
    auto* records = reinterpret_cast<shm::ParticleRecord*>(frame.data() + sizeof h);
    const FluidParticles& f = m.fluid;
    for (std::size_t i = 0; i < fluid_count; ++i) {
      records[i].position_m[0] = f.x[i], records[i].position_m[1] = f.y[i], records[i].position_m[2] = f.z[i];
      records[i].scalar = std::sqrt(f.vx[i] * f.vx[i] + f.vy[i] * f.vy[i] + f.vz[i] * f.vz[i]);
    }
    particles_writer.publish(frame.data(), frame.size());
    ++c.particle_frames;
  };

  // VTK frames (the batch writer) from the particles a frame's read-back has just brought to the
  // host: no read-back of their own on Vulkan. Written on this thread between two steps; what it
  // costs is in stats.json (longest_vtk_write_s, vtk_write_total_s; README "VTK frames"). A write
  // that fails (disk full) ends the export, said once, never the haptic run.
  auto export_vtk = [&] {
    if (!vtk_frames || !vtk_frames->due(solver->time_s())) return;
    const std::uint64_t write_start = shm::monotonic_ns();
    try {
      vtk_frames->write(m, solver->time_s());
    } catch (const std::exception& e) {
      c.vtk_error = e.what();
      log::Line(log::Level::warning) << "VTK export stopped after " << c.vtk_frames << " frames: " << e.what();
      vtk_frames.reset();
      return;
    }
    const double write_s = double(shm::monotonic_ns() - write_start) * 1e-9;
    c.vtk_frames = vtk_frames->written();
    c.vtk_write_max_s = std::max(c.vtk_write_max_s, write_s);
    c.vtk_write_total_s += write_s;
  };

  try {
    solver->sync_and_check_finite();
    publish_particles(start_ns);
    export_vtk();
    while (!g_stop.load()) {
      std::uint64_t now = shm::monotonic_ns();
      if (o.duration_s > 0 && now - start_ns >= static_cast<std::uint64_t>(o.duration_s * 1e9)) break;
      if (watchdog_ns && now >= next_watchdog_ns) {
        notifier.send("WATCHDOG=1");
        next_watchdog_ns = now + watchdog_ns;
      }
      // Follow the wall clock: step once the wall has reached the simulated time.
      const std::uint64_t sim_wall_ns = origin_ns + static_cast<std::uint64_t>(solver->time_s() * 1e9);
      if (now < sim_wall_ns) {
        samples_writer.heartbeat();
        sleep_until_ns(std::min<std::uint64_t>(sim_wall_ns, now + 20'000'000ull));
        continue;
      }
      const double lag_s = double(now - sim_wall_ns) * 1e-9;
      if (lag_s > o.max_lag_s) {
        // Cannot keep up: drop the backlog rather than pretend (the fluid runs slower than real time).
        if (c.lag_events == 0) {
          const double wall = std::max(double(now - start_ns) * 1e-9, 1e-9);
          char line[256];
          std::snprintf(line, sizeof line,
                        "WARNING cannot keep up with the wall clock (%.0f ms behind at t = %.2f s, "
                        "%.0f steps/s): the fluid runs SLOWER than real time; real-time factor so far %.2f, "
                        "reported in status lines and stats.json",
                        lag_s * 1e3, solver->time_s(), double(solver->steps()) / wall, solver->time_s() / wall);
          log::write(log::Level::warning, line);
        }
        ++c.lag_events;
        c.dropped_backlog_s += lag_s;
        origin_ns = now - static_cast<std::uint64_t>(solver->time_s() * 1e9);
      }

      // Device poses: the newest device_states record, matched by name (live_runner.hpp).
      if (const shm::DeviceStatesRecord* r = input.poll(now)) {
        devices = *r;
        have_devices = true;
        ++c.device_records;
        std::fill(live_device_of_scene.begin(), live_device_of_scene.end(), -1);
        const std::uint32_t n = std::min<std::uint32_t>(devices.device_count, shm::kMaxDevices);
        for (std::uint32_t i = 0; i < std::uint32_t(shm::kMaxDevices); ++i) {
          scene_device_of_entry[i] = -1;
          if (i >= n || !devices.devices[i].present) continue;
          const std::string name(devices.devices[i].name, strnlen(devices.devices[i].name, shm::kDeviceNameBytes));
          const int d = match_scene_device(scene, m, name);
          scene_device_of_entry[i] = d;
          if (d >= 0 && live_device_of_scene[d] < 0) live_device_of_scene[d] = static_cast<int>(i);
          const std::string mapping = d >= 0 ? name + " -> " + m.devices[d].name : name + " -> (none)";
          if (device_map[i] != mapping) {
            device_map[i] = mapping;
            if (d >= 0) log::Line(log::Level::info) << "rig device \"" << name << "\" drives scene device \"" << m.devices[d].name << "\"";
            else if (!unmatched_said[i])
              log::Line(log::Level::warning) << "rig device \"" << name
                                             << "\" drives no scene device (no scene device has rig_device = \"" << name
                                             << "\" or that name): it feels no fluid";
            unmatched_said[i] = d < 0;
          }
        }
      }
      const double dt = solver->stable_time_step();
      for (std::size_t d = 0; d < m.devices.size(); ++d) {
        const int i = live_device_of_scene[d];
        if (i >= 0 && input.live() && finite_entry(devices.devices[i])) {
          // Coupled at its pose at the step's end (coupling.hpp: device_state_after).
          held[d] = device_state_after(from_entry(devices.devices[i], centre[d]), dt);
        } else if (i >= 0) {
          held[d].linear_velocity = {}, held[d].angular_velocity = {};  // no fresh pose: hold still
        } else {
          const config::SceneDevice* sd = scene.find_device(m.devices[d].name);
          if (sd && sd->source == config::DeviceSource::scripted)
            held[d] = device_state_from(config::evaluate_motion(m.devices[d].motion, solver->time_s()));
        }
        solver->set_device_state(d, held[d]);
      }

      const int active_threads = thread_choice.threads() > 1 ? thread_choice.next() : thread_choice.threads();
      if (thread_choice.threads() > 1) solver->set_active_threads(active_threads);
      const std::uint64_t step_start = shm::monotonic_ns();
      solver->step(dt);
      now = shm::monotonic_ns();
      thread_choice.took(double(now - step_start) * 1e-9);
      c.step_wall_max_s = std::max(c.step_wall_max_s, double(now - step_start) * 1e-9);
      c.step_wall_total_s += double(now - step_start) * 1e-9;
      c.dt_min = std::min(c.dt_min, dt), c.dt_max = std::max(c.dt_max, dt);
      // The last-resort wall clamp is a fault of the step (the fluid outran its walls), not a fix:
      // said once when it first acts, then counted in status lines and stats.json.
      if (const std::uint64_t clamped = solver->clamped_particle_count(); clamped > 0 && c.clamped_reported == 0) {
        char line[320];
        std::snprintf(line, sizeof line,
                      "WARNING %llu fluid particle(s) reached a wall at t = %.3f s and were put back by "
                      "the last-resort clamp: the fluid moves faster than this step resolves; counted in status lines "
                      "and stats.json (clamped_particle_events)",
                      (unsigned long long)clamped, solver->time_s());
        log::write(log::Level::warning, line);
        c.clamped_reported = clamped;
      }

      // sim_samples: bodies and one coupling model per device_states entry (eq. of layouts.hpp).
      shm::SimSample& s = *sample;
      s.sequence = solver->steps();
      s.sim_time_s = solver->time_s();
      s.threads_active = cpu_backend ? static_cast<std::uint32_t>(active_threads) : 0;
      s.device_tick = have_devices ? devices.tick : 0;
      s.pose_lead_s = dt;  // held[]: device_state_after(the pose read, dt)
      s.body_count = static_cast<std::uint32_t>(std::min<std::size_t>(m.bodies.size(), shm::kMaxBodies));
      for (std::uint32_t b = 0; b < s.body_count; ++b) {
        const RigidBody& body = m.bodies[b];
        const config::Pose p = body.mesh_pose();
        s.bodies[b].position_m[0] = p.position_m.x, s.bodies[b].position_m[1] = p.position_m.y;
        s.bodies[b].position_m[2] = p.position_m.z;
        s.bodies[b].orientation[0] = p.orientation.w, s.bodies[b].orientation[1] = p.orientation.x;
        s.bodies[b].orientation[2] = p.orientation.y, s.bodies[b].orientation[3] = p.orientation.z;
        put3(body.linear_velocity, s.bodies[b].linear_velocity_m_s);
        put3(body.angular_velocity, s.bodies[b].angular_velocity_rad_s);
      }
      s.device_count = have_devices ? std::min<std::uint32_t>(devices.device_count, shm::kMaxDevices) : 0;
      for (std::uint32_t i = 0; i < std::uint32_t(shm::kMaxDevices); ++i) {
        shm::CouplingModel& cm = s.couplings[i];
        cm = {};
        const int d = i < s.device_count ? scene_device_of_entry[i] : -1;
        if (d < 0 || !input.live()) continue;
        const DeviceState& x0 = held[d];  // what set_device_state gave the step
        put3(x0.position - centre[d], cm.x0_m);  // back to the rig frame haptic-rt compares it in
        put4(x0.orientation, cm.q0);
        put3(x0.linear_velocity, cm.v0_m_s);
        put3(x0.angular_velocity, cm.w0_rad_s);
        Vec3 f, t, k_v, kr_w;
        for (const VirtualCoupling& vc : m.couplings) {
          if (vc.device != std::size_t(d)) continue;
          // The coupling's spring-damper is the local model of the hand's wrench (§4.4): on the
          // hand it is -K (x - x_grasp) + D (v_grasp - v), hence F = F0 - K (x - x0) + D (v0 - v),
          // with x_grasp moving on at the grasp's velocity until the next sample.
          f = f + vc.device_force, t = t + vc.device_torque;
          const RigidBody& body = m.bodies[vc.body];
          k_v = k_v + body.velocity_at(grasp_in_world(body, vc)) * vc.linear_stiffness_n_per_m;
          kr_w = kr_w + body.angular_velocity * vc.angular_stiffness_nm_per_rad;
          cm.stiffness_n_per_m += vc.linear_stiffness_n_per_m;
          cm.damping_n_s_per_m += vc.linear_damping_n_s_per_m;
          cm.angular_stiffness_nm_per_rad += vc.angular_stiffness_nm_per_rad;
          cm.angular_damping_nm_s_per_rad += vc.angular_damping_nm_s_per_rad;
          cm.valid = 1;
        }
        put3(f, cm.force_n);
        put3(t, cm.torque_nm);
        // One anchor for the device's springs: their grasps' twists, weighted as the springs pull.
        if (cm.stiffness_n_per_m > 0) put3(k_v * (1.0 / cm.stiffness_n_per_m), cm.vref_m_s);
        if (cm.angular_stiffness_nm_per_rad > 0) put3(kr_w * (1.0 / cm.angular_stiffness_nm_per_rad), cm.wref_rad_s);
      }
      s.publish_ns = shm::monotonic_ns();
      samples_writer.publish(s);
      ++c.samples;

      if (couplings_csv) {
        const std::string tail = "," + num(double(s.publish_ns - start_ns) * 1e-9) + "," + std::to_string(s.device_tick) +
                                 "," + std::to_string(s.publish_ns);
        for (const VirtualCoupling& vc : m.couplings)
          couplings_csv->row(coupling_row(m, vc, solver->time_s()) + tail);
      }
      if (solver->time_s() + 1e-9 >= next_frame_s) {
        // Once per frame: the particles come back (Vulkan) and a diverged fluid stops the run, named.
        solver->sync_and_check_finite();
        publish_particles(shm::monotonic_ns());
        export_vtk();
        next_frame_s += frame_period;
        if (next_frame_s < solver->time_s()) next_frame_s = solver->time_s() + frame_period;
      }
      if (bodies_csv && solver->time_s() + 1e-9 >= next_body_row_s) {
        next_body_row_s = solver->time_s() + frame_period;
        for (const RigidBody& b : m.bodies) bodies_csv->row(body_row(b, solver->time_s()));
      }
      if (o.status_every_s > 0 && now >= next_status_ns) {
        const double window = std::max(double(now - status_wall_ns) * 1e-9, 1e-9);
        char line[260];
        std::snprintf(line, sizeof line,
                      "t = %.2f s, %.0f steps/s, real-time factor %.2f, %d thread(s), %llu samples, "
                      "%llu frames%s%s",
                      solver->time_s(), double(solver->steps() - status_steps) / window,
                      (solver->time_s() - status_sim_s) / window, solver->active_threads(), (unsigned long long)c.samples,
                      (unsigned long long)c.particle_frames, clamp_note(solver->clamped_particle_count()).c_str(),
                      input.live() ? "" : ", no haptic-rt");
        log::write(log::Level::info, line);
        if (notifier.active()) notifier.send(std::string("STATUS=") + line);
        status_steps = solver->steps(), status_sim_s = solver->time_s(), status_wall_ns = now;
        next_status_ns = now + static_cast<std::uint64_t>(o.status_every_s * 1e9);
      }
    }
  } catch (const std::exception& e) {
    error = e.what();
  }
  notifier.send("STOPPING=1");
  const double wall_s = double(shm::monotonic_ns() - start_ns) * 1e-9;
  // Readers see `closed` and the names disappear (a crashed sim's segments are replaced by the next start).
  samples_writer.close();
  particles_writer.close();
  std::vector<std::string> matches;
  for (const auto& s : device_map)
    if (!s.empty()) matches.push_back(s);
  if (!o.out.empty()) {
    if (error.empty()) {
      if (couplings_csv) couplings_csv->finish();
      if (bodies_csv) bodies_csv->finish();
    }
    write_text_atomically(o.out / "stats.json", stats_json(o, backend, c, thread_choice, wall_s, matches, error.empty(), error));
  }
  char line[360];
  std::snprintf(line, sizeof line,
                "live run %s on the %s backend: %llu steps in %.2f s (%.0f steps/s), %.2f s simulated, "
                "real-time factor %.3f%s%s",
                error.empty() ? "stopped" : "FAILED", solver->backend(), (unsigned long long)solver->steps(), wall_s,
                double(solver->steps()) / std::max(wall_s, 1e-9), solver->time_s(), solver->time_s() / std::max(wall_s, 1e-9),
                c.lag_events ? " (could NOT keep up with the wall clock)" : "",
                clamp_note(solver->clamped_particle_count()).c_str());
  log::write(error.empty() ? log::Level::info : log::Level::error, line);
  if (!error.empty()) {
    log::Line(log::Level::error) << "error: " << error;
    return 1;
  }
  return 0;
}

}  // namespace hapfluid::sim
