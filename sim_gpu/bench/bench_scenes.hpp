// The benchmark scenes shared by bench_sim_cpu and bench_sim_vulkan, so `make bench` times both
// backends on exactly the same particles: the fluid pool of §6.2.1 (fig. 6a) and the pool with
// floating spheres of figs. 6b/6c, each written as a scene file and loaded like any other.
#pragma once

#include <cmath>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "hapfluid/config/mesh.hpp"
#include "hapfluid/config/scene.hpp"
#include "hapfluid/sim/mesh_sampling.hpp"
#include "hapfluid/sim/model.hpp"
#include "hapfluid/config/primitive_meshes.hpp"

namespace hapfluid::sim::bench {

struct Body { double x, y, z, radius, spacing; };

// A pool of `fluid_target` particles in a 1 x 1 m box, depth set by the particle count at a
// spacing chosen so that the full pool (pool_particles) is 0.25 m deep.
// `dfsph`: the pool at water's viscosity on the incompressible solver, stepped from the lattice
// (no settling), as the SPlisHSPlasH comparison runs it; otherwise wcsph at 0.5 Pa s.
inline config::Scene pool_scene(const std::filesystem::path& dir, int pool_particles, int fluid_target,
                                const std::vector<Body>& bodies, bool dfsph = false) {
  const double s = std::cbrt(0.25 / pool_particles);
  const double depth = fluid_target * s * s * s;
  std::ostringstream t;
  t << "name = \"pool\"\n[domain]\nmin_m = [0.0, 0.0, 0.0]\nmax_m = [1.0, 1.0, 0.5]\n"
    << "[fluid]\nparticle_spacing_m = " << s << "\n"
    << (dfsph ? "solver = \"dfsph\"\nsettle_s = 0.0\nviscosity_pa_s = 0.001\n"
              : "solver = \"wcsph\"\nspeed_of_sound_m_s = 20.0\nviscosity_pa_s = 0.5\n")
    << "[[fluid.blocks]]\nmin_m = [0.0, 0.0, 0.0]\nmax_m = [1.0, 1.0, " << depth << "]\n";
  for (std::size_t i = 0; i < bodies.size(); ++i) {
    config::save_obj(primitives::sphere_mesh(bodies[i].radius, 5), dir / ("sphere" + std::to_string(i) + ".obj"));
    t << "[[bodies]]\nname = \"sphere" << i << "\"\nmesh = \"sphere" << i << ".obj\"\nposition_m = [" << bodies[i].x << ", "
      << bodies[i].y << ", " << bodies[i].z << "]\ndensity_kg_m3 = 500.0\nsampling_spacing_m = " << bodies[i].spacing << "\n";
  }
  std::ofstream(dir / "scene.toml") << t.str();
  return config::load_scene(dir / "scene.toml");
}

// Surface sampling spacing that gives n particles on a sphere of radius r: a first guess from
// the area, corrected once from the count the sampler actually produces.
inline double sphere_spacing(int n, double r) {
  const auto mesh = primitives::sphere_mesh(r, 5);
  double spacing = std::sqrt(4 * 3.14159265 * r * r / n);
  for (int pass = 0; pass < 2; ++pass) {
    const double got = static_cast<double>(sample_surface(mesh, 1.0, spacing, 0.5 * spacing).size());
    spacing *= std::sqrt(got / n);
  }
  return spacing;
}

// A pool scene whose fluid is deepened so that fluid + body particles come to `total`
// (bodies displace fluid: the scene is built once to count, then adjusted).
inline config::Scene matched_scene(const std::filesystem::path& dir, int total, const std::vector<Body>& bodies) {
  int fluid_target = total;
  config::Scene scene = pool_scene(dir, total, fluid_target, bodies);
  for (int pass = 0; pass < 2; ++pass) {
    const SimulationModel m = build_model(scene);
    const int have = static_cast<int>(m.fluid.size() + m.body_particles.size());
    fluid_target += total - have;
    scene = pool_scene(dir, total, fluid_target, bodies);
  }
  return scene;
}

}  // namespace hapfluid::sim::bench
