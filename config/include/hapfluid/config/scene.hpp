// A scene file describes one simulation: the domain, the fluid, the rigid bodies (meshes), the
// devices that move them (live from a rig, or scripted hands) and the virtual couplings between
// devices and bodies. SI units throughout.
#pragma once

#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include "hapfluid/config/motion.hpp"
#include "hapfluid/config/types.hpp"

namespace hapfluid::config {

// The domain box. Each enabled wall is a layer of boundary particles; an open top lets fluid
// leave upward (it is then clamped by the box's extent so it can never escape the grid).
struct Walls {
  bool floor = true, ceiling = false;
  bool x_min = true, x_max = true, y_min = true, y_max = true;
};

struct Domain {
  Aabb box;  // z is up
  Walls walls;
  int boundary_layers = 2;  // layers of boundary particles behind each wall
};

struct FluidBlock {
  Aabb box;
  // A body the block is poured into: only lattice points with that body straight below them
  // (along gravity) are filled, so a box drawn around a bowl fills its inside up to the box's
  // top and not the air beside or beneath it. Empty: the whole box.
  std::string vessel;
};

// Visual preset for the renderer (§5, eq. 15): colour and wavelength-dependent extinction.
enum class FluidLook { water, batter, honey, syrup };

// The pressure solver. dfsph, the default: incompressible, divergence-free plus constant-density
// solves (Bender & Koschier 2017), time step from the flow velocity (CPU backend; sim_gpu/README.md
// says what does not hold yet). wcsph: the paper's weakly compressible state equation (eq. 7),
// time step from the speed of sound; the reference, and the Vulkan backend's.
enum class PressureSolver { wcsph, dfsph };

struct Fluid {
  PressureSolver solver = PressureSolver::dfsph;
  double rest_density_kg_m3 = 1000.0;
  double particle_spacing_m = 0.02;
  double support_radius_m = 0.0;   // h; 0: derived as 2 * particle_spacing_m
  // Pressure eq. 7: p = k (rho - rho0). Give either k directly or the speed of sound c
  // (then k = c^2). Exactly one of them is set after loading: stiffness_pa wins.
  double stiffness_pa = 0.0;       // k, in Pa per (kg/m^3) -> effectively m^2/s^2
  double speed_of_sound_m_s = 0.0;
  double viscosity_pa_s = 0.001;   // mu
  // dfsph: the solves iterate until the mean density error (constant-density solve) and the
  // mean density change over one step (divergence-free solve) are below these, in percent of
  // the rest density.
  double density_error_percent = 0.1;
  double divergence_error_percent = 0.1;
  int max_solver_iterations = 100;
  // XSPH velocity smoothing (Monaghan 1989): each step a particle's velocity moves this fraction
  // of the way to its neighbours' kernel-weighted mean. A numerical damping of particle noise,
  // not a physical viscosity; 0 disables it.
  double xsph_fraction = 0.0;
  // dfsph: before t = 0 the fluid is stepped this long (simulated) with its velocities damped
  // after every step and the bodies held: it starts at rest in the packing it relaxes to under
  // gravity. A cubic lattice is about 3 % looser than that packing for the cubic spline; started
  // from it, a column sinks by that much and the released energy sloshes at decimetres per second.
  double settle_s = 0.5;
  Vec3 gravity_m_s2{0, 0, -9.81};
  std::vector<FluidBlock> blocks;
  FluidLook look = FluidLook::water;

  // wcsph: k of eq. 7. dfsph: the stiffness of body-body and body-wall contacts only (the fluid is
  // incompressible); without speed_of_sound_m_s or stiffness_pa it is kDefaultContactSpeed_m_s^2.
  double effective_stiffness() const {
    if (stiffness_pa > 0) return stiffness_pa;
    if (speed_of_sound_m_s > 0) return speed_of_sound_m_s * speed_of_sound_m_s;
    return kDefaultContactSpeed_m_s * kDefaultContactSpeed_m_s;
  }
  static constexpr double kDefaultContactSpeed_m_s = 10.0;
};

struct TimeStepping {
  double dt_s = 0.0;             // fixed step; 0: from the CFL bound
  // wcsph: dt = cfl * h / (c + v_max), h the support radius; dfsph: dt = cfl * d / v_max, d the
  // particle spacing. Both are also bounded by the viscosity, force and contact limits. 0 until
  // loaded: the default depends on the solver (kDefaultCflWcsph, kDefaultCflDfsph).
  double cfl = 0.0;
  static constexpr double kDefaultCflWcsph = 0.15, kDefaultCflDfsph = 0.4;
  double max_dt_s = 0.002;
  double frame_rate_hz = 60.0;   // published frames (and batch exports); several substeps per frame
};

// A body is a sampled mesh (§4, a rigid body of boundary particles) or a single particle
// (§3.2, Algorithm 1: the probe of a 3-DoF device, sized like a fluid particle).
enum class BodyShape { mesh, particle };

struct Body {
  std::string name;
  BodyShape shape = BodyShape::mesh;
  std::filesystem::path mesh;  // resolved against the scene file's folder; empty for a particle
  double scale = 1.0;
  Pose pose;                   // pose of the mesh frame in the world
  double density_kg_m3 = 0.0;  // one of density / mass
  double mass_kg = 0.0;
  double viscosity_pa_s = 0.0; // eq. 9: the body's own viscosity; 0: the fluid's
  double sampling_spacing_m = 0.0;  // 0: the fluid particle spacing
  bool dynamic = true;         // static bodies never move (tables, fixed containers)
};

enum class DeviceSource { rig, scripted };

struct SceneDevice {
  std::string name;
  DeviceSource source = DeviceSource::scripted;
  std::string rig_device;      // source = rig: the rig device's name
  ScriptedMotion motion;       // source = scripted (also the start pose for rig devices)
  // Live: the scene point where the rig frame's origin lands (x_scene = x_rig + this), so a
  // device's workspace, centred on its rig-frame origin, surrounds the scene's hand whatever
  // the scene's coordinates. Default: the start position (the hand starts at the centre).
  Vec3 workspace_centre_m;
};

// rigid: 6-DoF, force and torque (Algorithm 2); probe: 3-DoF, the device holds a particle body
// at its centre and renders forces only, zero torque (Algorithm 1, lines 17-22).
enum class CouplingKind { rigid, probe };

struct Coupling {
  std::string device;
  std::string body;
  CouplingKind kind = CouplingKind::rigid;
  Pose grasp;                  // device handle pose in the body frame (where the hand holds it)
  double linear_stiffness_n_per_m = 500.0;
  double linear_damping_n_s_per_m = 5.0;
  double angular_stiffness_nm_per_rad = 5.0;
  double angular_damping_nm_s_per_rad = 0.05;
};

struct Scene {
  std::filesystem::path file;
  std::string name;
  std::string description;
  double duration_s = 10.0;    // default length of a batch or live run
  Domain domain;
  Fluid fluid;
  TimeStepping time;
  std::vector<Body> bodies;
  std::vector<SceneDevice> devices;
  std::vector<Coupling> couplings;

  double support_radius() const {
    return fluid.support_radius_m > 0 ? fluid.support_radius_m : 2.0 * fluid.particle_spacing_m;
  }
  const Body* find_body(const std::string& name) const;
  const SceneDevice* find_device(const std::string& name) const;
};

// Throws ConfigError listing every problem in the file. Mesh files are checked for existence
// and readability, and bodies are checked against the domain using the mesh bounds.
Scene load_scene(const std::filesystem::path& file);
Scene parse_scene(const std::string& toml_text, const std::filesystem::path& file_for_messages);

const char* to_string(FluidLook);
const char* to_string(PressureSolver);
const char* to_string(DeviceSource);

}  // namespace hapfluid::config
