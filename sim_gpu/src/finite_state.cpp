#include "hapfluid/sim/finite_state.hpp"

#include <cmath>
#include <cstdio>
#include <stdexcept>
#include <string>

namespace hapfluid::sim {
namespace {

std::string fmt(double v) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%g", v);
  return buf;
}

// Whole strings from snprintf: GCC 12 warns falsely (-Wrestrict) on "(" + std::string.
std::string fmt(double x, double y, double z) {
  char buf[96];
  std::snprintf(buf, sizeof buf, "(%g, %g, %g)", x, y, z);
  return buf;
}

std::string fmt(const Quat& q) {
  char buf[128];
  std::snprintf(buf, sizeof buf, "[%g, %g, %g, %g]", q.w, q.x, q.y, q.z);
  return buf;
}

bool finite3(double x, double y, double z) { return std::isfinite(x) && std::isfinite(y) && std::isfinite(z); }

// The scene keys that shorten the step: the fixed step when the scene sets one, else the CFL keys.
std::string time_step_fix(const SimulationParams& p) {
  if (p.fixed_dt_s > 0) return "lower time.dt_s (" + fmt(p.fixed_dt_s) + " s; 0 chooses a stable CFL step)";
  return "lower time.cfl (" + fmt(p.cfl) + ") or time.max_dt_s (" + fmt(p.max_dt_s) + " s)";
}

[[noreturn]] void diverged(double time_s, const std::string& what, const std::string& quantity, const std::string& value,
                           const std::string& fix) {
  throw std::runtime_error("simulation diverged at t = " + fmt(time_s) + " s: " + what + ": " + quantity + " " + value +
                           " is not finite: " + fix);
}

}  // namespace

void check_finite_state(const SimulationModel& m, double time_s) {
  const FluidParticles& f = m.fluid;
  const std::string fluid_fix =
      time_step_fix(m.params) + ", or the stiffness (fluid.speed_of_sound_m_s or fluid.stiffness_pa)";
  for (std::size_t i = 0; i < f.size(); ++i) {
    const std::string what = "fluid particle " + std::to_string(f.id[i]);
    if (!finite3(f.x[i], f.y[i], f.z[i])) diverged(time_s, what, "position", fmt(f.x[i], f.y[i], f.z[i]) + " m", fluid_fix);
    if (!finite3(f.vx[i], f.vy[i], f.vz[i]))
      diverged(time_s, what, "velocity", fmt(f.vx[i], f.vy[i], f.vz[i]) + " m/s at " + fmt(f.x[i], f.y[i], f.z[i]) + " m",
               fluid_fix);
  }
  const std::string body_fix = time_step_fix(m.params) + ", or the coupling gains";
  for (const RigidBody& b : m.bodies) {
    if (!b.dynamic) continue;
    const std::string what = "body " + b.name;
    const Quat& q = b.orientation;
    if (!finite(b.position)) diverged(time_s, what, "position", fmt(b.position.x, b.position.y, b.position.z) + " m", body_fix);
    if (!std::isfinite(q.w) || !finite3(q.x, q.y, q.z))
      diverged(time_s, what, "orientation", fmt(q), body_fix);
    const Vec3 &v = b.linear_velocity, &w = b.angular_velocity;
    if (!finite(v)) diverged(time_s, what, "velocity", fmt(v.x, v.y, v.z) + " m/s", body_fix);
    if (!finite(w)) diverged(time_s, what, "angular velocity", fmt(w.x, w.y, w.z) + " rad/s", body_fix);
  }
  // Body particles are floats placed from the (double) body state: a body gone far enough is
  // finite as a body and not as particles.
  const BodyParticles& bp = m.body_particles;
  for (std::size_t i = 0; i < bp.size(); ++i)
    if (!finite3(bp.x[i], bp.y[i], bp.z[i]) || !finite3(bp.vx[i], bp.vy[i], bp.vz[i]))
      diverged(time_s, "body " + m.bodies[bp.body[i]].name + ", particle " + std::to_string(i), "position and velocity",
               fmt(bp.x[i], bp.y[i], bp.z[i]) + " m, " + fmt(bp.vx[i], bp.vy[i], bp.vz[i]) + " m/s", body_fix);
}

}  // namespace hapfluid::sim
