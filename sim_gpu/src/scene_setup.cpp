// From a loaded scene to particles and bodies: domain walls, mesh bodies sampled into particles
// with their mass properties, fluid blocks filled on a lattice, devices and couplings.
#include <algorithm>
#include <cmath>
#include <sstream>
#include <stdexcept>

#include "hapfluid/config/mesh.hpp"
#include "hapfluid/sim/boundary.hpp"
#include "hapfluid/sim/contact_damping.hpp"
#include "hapfluid/sim/mesh_sampling.hpp"
#include "hapfluid/sim/model.hpp"

namespace hapfluid::sim {
namespace {

std::string fmt(double v) {
  std::ostringstream s;
  s << v;
  return s.str();
}

constexpr double kBoundaryInsetSpacings = 0.65;

[[noreturn]] void fail(const config::Scene& scene, const std::string& what) {
  throw std::runtime_error(scene.file.string() + ": " + what);
}

struct SolidSource {
  std::vector<Vec3> positions;
  std::vector<float> volumes;
  std::int32_t body = kWall;
  float viscosity = 0, no_slip = 0;
};

// Fails when a dynamic body's particles come closer than half a spacing to an enabled wall
// (it would start inside the wall's boundary particles and be shot out).
void check_clear_of_walls(const config::Scene& scene, const std::string& name, const std::vector<Vec3>& world, double s) {
  const auto& b = scene.domain.box;
  const auto& w = scene.domain.walls;
  struct Plane { bool on; int axis; double at; double sign; const char* label; };
  const Plane planes[6] = {{w.x_min, 0, b.min_m.x, 1, "x_min"}, {w.x_max, 0, b.max_m.x, -1, "x_max"},
                           {w.y_min, 1, b.min_m.y, 1, "y_min"}, {w.y_max, 1, b.max_m.y, -1, "y_max"},
                           {w.floor, 2, b.min_m.z, 1, "floor"}, {w.ceiling, 2, b.max_m.z, -1, "ceiling"}};
  for (const Plane& p : planes) {
    if (!p.on) continue;
    for (const Vec3& x : world) {
      const double clearance = (x[p.axis] - p.at) * p.sign;
      if (clearance < 0.5 * s)
        fail(scene, "bodies." + name + ": the body overlaps the domain wall " + p.label + " (a surface point is " +
                        fmt(clearance) + " m from it; keep every body at least half a particle spacing, " +
                        fmt(0.5 * s) + " m, inside the domain box)");
    }
  }
}

// A device's probe (Algorithm 1): one particle treated as a particle of the fluid, with the
// fluid particle's volume m / rho0 (so a probe of the fluid's density is neutrally buoyant)
// and its mass from the body's density or mass. Its inertia, that of a sphere of half a
// spacing, only keeps the body step's 6x6 solve regular: a particle at the centre of mass
// turns with nothing.
RigidBody particle_body(const config::Scene& scene, const SimulationParams& p, const config::Body& cb, std::int32_t index,
                        BodyParticles& bp) {
  const double volume = p.fluid_particle_mass_kg / p.rest_density_kg_m3;
  RigidBody body;
  body.name = cb.name;
  body.dynamic = true;
  body.volume_m3 = volume;
  body.viscosity_pa_s = cb.viscosity_pa_s > 0 ? cb.viscosity_pa_s : scene.fluid.viscosity_pa_s;
  body.com_in_mesh_frame = {0, 0, 0};
  body.orientation = Quat{};
  body.position = from_config(cb.pose.position_m);
  body.mass_kg = cb.mass_kg > 0 ? cb.mass_kg : cb.density_kg_m3 * volume;
  const double radius = 0.5 * p.particle_spacing_m, moment = 0.4 * body.mass_kg * radius * radius;
  for (int i = 0; i < 3; ++i) body.inertia_body.m[i][i] = moment;
  body.inertia_body_inverse = inverse(body.inertia_body);
  body.first_particle = static_cast<std::uint32_t>(bp.size());
  body.particle_count = 1;
  bp.resize(bp.size() + 1);
  const std::size_t i = body.first_particle;
  bp.rx[i] = bp.ry[i] = bp.rz[i] = 0;
  bp.x[i] = static_cast<float>(body.position.x), bp.y[i] = static_cast<float>(body.position.y),
  bp.z[i] = static_cast<float>(body.position.z);
  bp.volume[i] = static_cast<float>(volume);
  bp.viscosity[i] = static_cast<float>(body.viscosity_pa_s);
  bp.body[i] = index;
  return body;
}

void fill_sorted_solids(const std::vector<SolidSource>& sources, const GridGeometry& grid, SortedSolids& out) {
  std::vector<float> x, y, z, volume, viscosity, no_slip;
  std::vector<std::int32_t> body;
  for (const auto& s : sources)
    for (std::size_t i = 0; i < s.positions.size(); ++i) {
      x.push_back(static_cast<float>(s.positions[i].x));
      y.push_back(static_cast<float>(s.positions[i].y));
      z.push_back(static_cast<float>(s.positions[i].z));
      volume.push_back(s.volumes[i]);
      viscosity.push_back(s.viscosity);
      no_slip.push_back(s.no_slip);
      body.push_back(s.body);
    }
  CellSort sort;
  sort.sort(grid, x.data(), y.data(), z.data(), x.size());
  out.resize(x.size());
  for (std::size_t k = 0; k < x.size(); ++k) {
    const std::uint32_t i = sort.order[k];
    out.x[k] = x[i], out.y[k] = y[i], out.z[k] = z[i];
    out.vx[k] = out.vy[k] = out.vz[k] = 0;
    out.volume[k] = volume[i], out.viscosity[k] = viscosity[i], out.no_slip[k] = no_slip[i];
    out.pressure[k] = 0;
    out.body[k] = body[i];
    out.source[k] = i;
  }
  out.cell_start = sort.cell_start;
}

}  // namespace

double lattice_particle_mass(double rest_density, double spacing, double h) {
  const int reach = static_cast<int>(std::ceil(h / spacing));
  double sum = 0;
  for (int i = -reach; i <= reach; ++i)
    for (int j = -reach; j <= reach; ++j)
      for (int k = -reach; k <= reach; ++k)
        sum += poly6_d(spacing * std::sqrt(static_cast<double>(i * i + j * j + k * k)), h);
  return rest_density / sum;
}

double cubic_lattice_particle_mass(double rest_density, double spacing, double h) {
  const int reach = static_cast<int>(std::ceil(h / spacing));
  double sum = 0;
  for (int i = -reach; i <= reach; ++i)
    for (int j = -reach; j <= reach; ++j)
      for (int k = -reach; k <= reach; ++k)
        sum += cubic_w_d(spacing * std::sqrt(static_cast<double>(i * i + j * j + k * k)), h);
  return rest_density / sum;
}

double cubic_lattice_gradient_moment(double spacing, double h) {
  // sum_j V (z_j - z_i) dW/dz_i over a cubic lattice with V = 1 / sum_j W (the lattice volume at
  // rest density): 1 for an exact gradient, 1.020 for the cubic spline at h = 2 spacings.
  const int reach = static_cast<int>(std::ceil(h / spacing));
  double sum = 0, weights = 0;
  for (int i = -reach; i <= reach; ++i)
    for (int j = -reach; j <= reach; ++j)
      for (int k = -reach; k <= reach; ++k) {
        const double r = spacing * std::sqrt(static_cast<double>(i * i + j * j + k * k));
        weights += cubic_w_d(r, h);
        if (r <= 0 || r >= h) continue;
        const double z = k * spacing;
        sum += z * cubic_dw_dr_d(r, h) * z / r;
      }
  return -sum / weights;
}

double lattice_gradient_moment(double spacing, double h) {
  // sum_j V (z_j - z_i) dW/dz_i over a cubic lattice: 1 for an exact gradient, about 0.956 for
  // the spiky kernel at h = 2 spacings.
  const int reach = static_cast<int>(std::ceil(h / spacing));
  double sum = 0;
  for (int i = -reach; i <= reach; ++i)
    for (int j = -reach; j <= reach; ++j)
      for (int k = -reach; k <= reach; ++k) {
        const double r = spacing * std::sqrt(static_cast<double>(i * i + j * j + k * k));
        if (r <= 0 || r >= h) continue;
        const double z = k * spacing;
        sum += spacing * spacing * spacing * z * spiky_grad_d(r, h) * z / r;
      }
  return -sum;
}

SimulationModel build_model(const config::Scene& scene) {
  SimulationModel model;
  model.scene_name = scene.name;
  SimulationParams& p = model.params;
  const double h = scene.support_radius();
  const double s = scene.fluid.particle_spacing_m;
  const bool incompressible = scene.fluid.solver == config::PressureSolver::dfsph;
  p.solver = scene.fluid.solver;
  p.kernel = make_kernel_constants(h);
  // The spiky gradient is scaled so that the pressure gradient estimate is exact on the rest
  // lattice (as the particle mass is chosen so that the density is): without it the fluid at
  // rest carries about 5-10% more pressure than rho0 g depth.
  p.kernel.spiky_grad = static_cast<float>(p.kernel.spiky_grad / lattice_gradient_moment(s, h));
  p.rest_density_kg_m3 = static_cast<float>(scene.fluid.rest_density_kg_m3);
  p.stiffness = static_cast<float>(scene.fluid.effective_stiffness());
  p.speed_of_sound_m_s = std::sqrt(p.stiffness);
  p.contact_damping_pa_s = static_cast<float>(contact_damping_scale(p.rest_density_kg_m3, p.speed_of_sound_m_s, h));
  p.particle_spacing_m = static_cast<float>(s);
  p.fluid_particle_mass_kg = static_cast<float>(incompressible ? cubic_lattice_particle_mass(scene.fluid.rest_density_kg_m3, s, h)
                                                               : lattice_particle_mass(scene.fluid.rest_density_kg_m3, s, h));
  if (incompressible) {
    IncompressibleParams& ip = p.incompressible;
    ip.kernel = make_cubic_kernel(h, cubic_lattice_gradient_moment(s, h));
    ip.max_density_error = static_cast<float>(scene.fluid.density_error_percent / 100.0);
    ip.max_divergence_error = static_cast<float>(scene.fluid.divergence_error_percent / 100.0);
    ip.max_iterations = scene.fluid.max_solver_iterations;
    ip.xsph_fraction = static_cast<float>(scene.fluid.xsph_fraction);
    ip.settle_s = scene.fluid.settle_s;
  }
  p.fluid_viscosity_pa_s = static_cast<float>(scene.fluid.viscosity_pa_s);
  p.gravity_m_s2 = from_config(scene.fluid.gravity_m_s2);
  const auto& box = scene.domain.box;
  const double lo[3] = {box.min_m.x, box.min_m.y, box.min_m.z}, hi[3] = {box.max_m.x, box.max_m.y, box.max_m.z};
  float glo[3], ghi[3];
  // dfsph: the fluid sees the walls through their volume map (wall_map.hpp); one layer of wall
  // particles remains for body contacts and the outputs.
  const int wall_layers = incompressible ? 1 : scene.domain.boundary_layers;
  const double margin = (wall_layers + 1) * s;
  for (int a = 0; a < 3; ++a) {
    p.box_lo[a] = static_cast<float>(lo[a]);
    p.box_hi[a] = static_cast<float>(hi[a]);
    glo[a] = static_cast<float>(lo[a] - margin);
    ghi[a] = static_cast<float>(hi[a] + margin);
  }
  p.grid = make_grid(glo, ghi, static_cast<float>(h));
  const auto& w = scene.domain.walls;
  const bool low_wall[3] = {w.x_min, w.y_min, w.floor}, high_wall[3] = {w.x_max, w.y_max, w.ceiling};
  for (int a = 0; a < 3; ++a) {
    p.clamp_lo[a] = static_cast<float>(low_wall[a] ? lo[a] - 0.5 * s : lo[a]);
    p.clamp_hi[a] = static_cast<float>(high_wall[a] ? hi[a] + 0.5 * s : hi[a]);
  }
  p.fixed_dt_s = scene.time.dt_s;
  p.cfl = scene.time.cfl;
  p.max_dt_s = scene.time.max_dt_s;
  p.frame_rate_hz = scene.time.frame_rate_hz;

  // Domain walls.
  std::vector<SolidSource> static_sources;
  {
    SolidSource walls;
    walls.positions = wall_particle_positions(scene.domain, s, wall_layers);
    // Wall layers lie on a continuation of the fluid's rest lattice. When they are at least h
    // thick a fluid particle sees a complete lattice across the wall, so each wall particle
    // stands for exactly the lattice volume m / rho0. Thinner walls use Akinci's volumes,
    // which enlarge the first layer to make up for the missing ones.
    if (wall_layers * s >= h * (1 - 1e-9))
      walls.volumes.assign(walls.positions.size(), p.fluid_particle_mass_kg / p.rest_density_kg_m3);
    else
      walls.volumes = boundary_volumes(walls.positions, p.kernel);
    walls.body = kWall;
    walls.viscosity = p.fluid_viscosity_pa_s;
    // Walls take part in eq. 9 with the fluid's viscosity like any other particle: without it
    // nothing damps the fluid's motion relative to the walls and a column at rest keeps moving.
    walls.no_slip = 1;
    model.wall_particle_count = walls.positions.size();
    static_sources.push_back(std::move(walls));
  }

  // Bodies.
  struct PlacedMesh { std::string name; config::TriangleMesh mesh; std::vector<Vec3> vertices; Vec3 origin; Quat orientation; Vec3 lo, hi; };
  std::vector<PlacedMesh> placed;
  std::vector<Vec3> all_solid_world;  // for clearing fluid off solids
  for (std::size_t bi = 0; bi < scene.bodies.size(); ++bi) {
    const config::Body& cb = scene.bodies[bi];
    if (cb.shape == config::BodyShape::particle) {
      model.bodies.push_back(particle_body(scene, p, cb, static_cast<std::int32_t>(bi), model.body_particles));
      const Vec3 x = from_config(cb.pose.position_m);
      check_clear_of_walls(scene, cb.name, {x}, s);
      all_solid_world.push_back(x);
      continue;
    }
    const std::string what = scene.file.string() + ": bodies." + cb.name;
    config::TriangleMesh mesh = config::load_mesh(cb.mesh);
    check_closed_mesh(mesh, what + " (" + cb.mesh.string() + ")");
    const double spacing = cb.sampling_spacing_m > 0 ? cb.sampling_spacing_m : s;
    if (spacing > h)
      fail(scene, "bodies." + cb.name + ": sampling spacing " + fmt(spacing) + " m is larger than the support radius h = " +
                      fmt(h) + " m: fluid would leak between the body's particles; use sampling_spacing_m <= " + fmt(h));
    const MassProperties mp = mass_properties(mesh, cb.scale);
    // Fluid particles rest about 1.15 fluid spacings from a single layer of boundary particles
    // (where the layer's Akinci contribution fills their density up to rho0), so the fluid's
    // own surface, half a spacing nearer, lies 0.65 spacings from the layer: sampling that far
    // inside the mesh puts it on the mesh surface.
    const std::vector<Vec3> samples = sample_surface(mesh, cb.scale, spacing, kBoundaryInsetSpacings * s);
    const config::Aabb bounds = config::transformed_bounds(mesh, cb.scale, config::Pose{});
    const double extent = std::max({bounds.max_m.x - bounds.min_m.x, bounds.max_m.y - bounds.min_m.y,
                                    bounds.max_m.z - bounds.min_m.z});
    // In the mesh's own frame: the loader's check (config/src/scene.cpp) sees the placed bounds,
    // which a rotation widens.
    if (extent < 3 * spacing)
      fail(scene, "bodies." + cb.name + ": particle spacing " + fmt(spacing) + " m is too large for the mesh (largest extent " +
                      fmt(extent) + " m): the body would be fewer than 3 particles across; use a sampling_spacing_m of at most " +
                      fmt(extent / 3) + " m");
    if (samples.size() < 8)
      fail(scene, "bodies." + cb.name + ": particle spacing " + fmt(spacing) + " m leaves only " +
                      std::to_string(samples.size()) + " surface particles on the mesh (at least 8 are needed); use a " +
                      "smaller sampling_spacing_m, e.g. " + fmt(spacing / 2) + " m");
    const Quat q = from_config(cb.pose.orientation);
    const Vec3 origin = from_config(cb.pose.position_m);
    const Mat3 r = rotation_matrix(q);
    std::vector<Vec3> world;
    world.reserve(samples.size());
    for (const Vec3& x : samples) world.push_back(origin + r * x);
    if (cb.dynamic) check_clear_of_walls(scene, cb.name, world, s);
    std::vector<float> volumes =
        incompressible ? boundary_volumes(world, p.incompressible.kernel) : boundary_volumes(world, p.kernel);

    RigidBody body;
    body.name = cb.name;
    body.dynamic = cb.dynamic;
    body.volume_m3 = mp.volume_m3;
    body.viscosity_pa_s = cb.viscosity_pa_s > 0 ? cb.viscosity_pa_s : scene.fluid.viscosity_pa_s;
    body.com_in_mesh_frame = mp.centre_of_mass_m;
    body.orientation = q;
    body.position = origin + r * mp.centre_of_mass_m;
    if (cb.dynamic) {
      const double density = cb.mass_kg > 0 ? cb.mass_kg / mp.volume_m3 : cb.density_kg_m3;
      body.mass_kg = density * mp.volume_m3;
      for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j) body.inertia_body.m[i][j] = mp.inertia_per_density.m[i][j] * density;
      body.inertia_body_inverse = inverse(body.inertia_body);
      BodyParticles& bp = model.body_particles;
      body.first_particle = static_cast<std::uint32_t>(bp.size());
      body.particle_count = static_cast<std::uint32_t>(samples.size());
      bp.resize(bp.size() + samples.size());
      for (std::size_t k = 0; k < samples.size(); ++k) {
        const std::size_t i = body.first_particle + k;
        const Vec3 rest = samples[k] - mp.centre_of_mass_m;
        bp.rx[i] = static_cast<float>(rest.x), bp.ry[i] = static_cast<float>(rest.y), bp.rz[i] = static_cast<float>(rest.z);
        bp.x[i] = static_cast<float>(world[k].x), bp.y[i] = static_cast<float>(world[k].y), bp.z[i] = static_cast<float>(world[k].z);
        bp.volume[i] = volumes[k];
        bp.viscosity[i] = static_cast<float>(body.viscosity_pa_s);
        bp.body[i] = static_cast<std::int32_t>(bi);
      }
    } else {
      SolidSource src;
      src.positions = world;
      src.volumes = volumes;
      src.body = static_cast<std::int32_t>(bi);
      src.viscosity = static_cast<float>(body.viscosity_pa_s);
      src.no_slip = 1;
      model.static_body_particle_count += world.size();
      static_sources.push_back(std::move(src));
    }
    all_solid_world.insert(all_solid_world.end(), world.begin(), world.end());
    PlacedMesh pm{cb.name, mesh, scaled_vertices(mesh, cb.scale), origin, q, {}, {}};
    pm.lo = pm.hi = pm.vertices.front();
    for (const Vec3& v : pm.vertices) {
      pm.lo = {std::min(pm.lo.x, v.x), std::min(pm.lo.y, v.y), std::min(pm.lo.z, v.z)};
      pm.hi = {std::max(pm.hi.x, v.x), std::max(pm.hi.y, v.y), std::max(pm.hi.z, v.z)};
    }
    placed.push_back(std::move(pm));
    model.bodies.push_back(std::move(body));
  }
  fill_sorted_solids(static_sources, p.grid, model.static_solids);

  // Fluid blocks on a lattice of the particle spacing, minus what lies inside a body or within
  // 0.75 spacing of a body particle (it would start compressed against the surface).
  {
    std::vector<float> sx, sy, sz;
    for (const Vec3& v : all_solid_world) {
      sx.push_back(static_cast<float>(v.x)), sy.push_back(static_cast<float>(v.y)), sz.push_back(static_cast<float>(v.z));
    }
    CellSort solid_sort;
    solid_sort.sort(p.grid, sx.data(), sy.data(), sz.data(), sx.size());
    const float clear2 = static_cast<float>(0.75 * s * 0.75 * s);
    std::vector<Vec3> fluid;
    // Blocks start compressed as at hydrostatic rest under gravity along -z (rho = rho0 (1 +
    // g d / c^2) at depth d, eq. 7): a lattice at rest density would first fall by g H / c^2 of
    // its height and ring, scrambling the lattice. z' = zb + u - (g / c^2) (H u - u^2 / 2), u = z - zb.
    const double g_down = p.gravity_m_s2.x == 0 && p.gravity_m_s2.y == 0 && p.gravity_m_s2.z < 0 ? -p.gravity_m_s2.z : 0.0;
    // (The incompressible solver starts at rest density.)
    const double squeeze = incompressible ? 0.0 : g_down / static_cast<double>(p.stiffness);
    auto hydrostatic_height = [&](double zb, double zt, double z) {
      const double u = z - zb, height = zt - zb;
      return zb + u - squeeze * (height * u - 0.5 * u * u);
    };
    // Down, for a block poured into a vessel: along gravity (the loader refuses a vessel
    // without gravity).
    const double g_norm = std::sqrt(dot(p.gravity_m_s2, p.gravity_m_s2));
    const Vec3 down = g_norm > 0 ? p.gravity_m_s2 * (1.0 / g_norm) : Vec3{0, 0, -1};
    for (std::size_t bi = 0; bi < scene.fluid.blocks.size(); ++bi) {
      const auto& b = scene.fluid.blocks[bi].box;
      const PlacedMesh* vessel = nullptr;
      for (const PlacedMesh& pm : placed)
        if (!scene.fluid.blocks[bi].vessel.empty() && pm.name == scene.fluid.blocks[bi].vessel) vessel = &pm;
      const Mat3 to_vessel = vessel ? transpose(rotation_matrix(vessel->orientation)) : Mat3{};
      const Vec3 vessel_down = to_vessel * down;
      for (double z = b.min_m.z + 0.5 * s; z < b.max_m.z; z += s)
        for (double y = b.min_m.y + 0.5 * s; y < b.max_m.y; y += s)
          for (double x = b.min_m.x + 0.5 * s; x < b.max_m.x; x += s) {
            bool taken = false;
            for (std::size_t e = 0; e < bi && !taken; ++e) {
              const auto& o = scene.fluid.blocks[e].box;
              taken = x > o.min_m.x && x < o.max_m.x && y > o.min_m.y && y < o.max_m.y && z > o.min_m.z && z < o.max_m.z;
            }
            if (taken) continue;
            if (vessel) {
              const Vec3 local = to_vessel * (Vec3{x, y, z} - vessel->origin);
              if (ray_crossings(vessel->vertices, vessel->mesh, local, vessel_down) == 0) continue;
            }
            const float fx = static_cast<float>(x), fy = static_cast<float>(y), fz = static_cast<float>(z);
            bool near = false;
            for_each_neighbour_run(p.grid, solid_sort.cell_start.data(), fx, fy, fz, [&](std::uint32_t b0, std::uint32_t e0) {
              for (std::uint32_t k = b0; k < e0 && !near; ++k) {
                const std::uint32_t i = solid_sort.order[k];
                const float dx = fx - sx[i], dy = fy - sy[i], dz = fz - sz[i];
                near = dx * dx + dy * dy + dz * dz < clear2;
              }
            });
            if (near) continue;
            for (const PlacedMesh& pm : placed) {
              const Vec3 local = transpose(rotation_matrix(pm.orientation)) * (Vec3{x, y, z} - pm.origin);
              if (local.x < pm.lo.x || local.y < pm.lo.y || local.z < pm.lo.z || local.x > pm.hi.x || local.y > pm.hi.y ||
                  local.z > pm.hi.z)
                continue;
              if (inside_closed_mesh(pm.vertices, pm.mesh, local)) {
                near = true;
                break;
              }
            }
            if (!near) fluid.push_back({x, y, hydrostatic_height(b.min_m.z, b.max_m.z, z)});
          }
    }
    FluidParticles& f = model.fluid;
    f.resize(fluid.size());
    for (std::size_t i = 0; i < fluid.size(); ++i) {
      f.x[i] = static_cast<float>(fluid[i].x), f.y[i] = static_cast<float>(fluid[i].y), f.z[i] = static_cast<float>(fluid[i].z);
      f.viscosity[i] = p.fluid_viscosity_pa_s;
      f.density[i] = p.rest_density_kg_m3;
      f.volume[i] = p.fluid_particle_mass_kg / p.rest_density_kg_m3;
      f.id[i] = static_cast<std::uint32_t>(i);
    }
  }

  // Devices and couplings.
  for (const auto& d : scene.devices) model.devices.push_back({d.name, d.motion});
  for (const auto& c : scene.couplings) {
    VirtualCoupling vc;
    for (std::size_t i = 0; i < scene.devices.size(); ++i)
      if (scene.devices[i].name == c.device) vc.device = i;
    for (std::size_t i = 0; i < scene.bodies.size(); ++i)
      if (scene.bodies[i].name == c.body) vc.body = i;
    // A probe is held at its particle (the body's centre): the spring pulls through the centre
    // of mass and no torque reaches the device.
    vc.grasp_position = c.kind == config::CouplingKind::probe ? model.bodies[vc.body].com_in_mesh_frame
                                                              : from_config(c.grasp.position_m);
    vc.grasp_orientation = from_config(c.grasp.orientation);
    vc.linear_stiffness_n_per_m = c.linear_stiffness_n_per_m;
    vc.linear_damping_n_s_per_m = c.linear_damping_n_s_per_m;
    vc.angular_stiffness_nm_per_rad = c.angular_stiffness_nm_per_rad;
    vc.angular_damping_nm_s_per_rad = c.angular_damping_nm_s_per_rad;
    model.couplings.push_back(vc);
  }
  return model;
}

}  // namespace hapfluid::sim
