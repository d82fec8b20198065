// Scene file schema and validation. docs/config-reference.md documents every key.
#include "hapfluid/config/scene.hpp"

#include <algorithm>
#include <map>
#include <set>

#include "hapfluid/config/mesh.hpp"
#include "load_toml.hpp"
#include "toml_reader.hpp"

namespace hapfluid::config {
namespace {

using detail::Reader;

std::string fmt(double v) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%g", v);
  return buf;
}
std::string fmt(const Vec3& v) { return "[" + fmt(v.x) + ", " + fmt(v.y) + ", " + fmt(v.z) + "]"; }

bool inside(const Aabb& inner, const Aabb& outer, double slack) {
  return inner.min_m.x >= outer.min_m.x - slack && inner.min_m.y >= outer.min_m.y - slack &&
         inner.min_m.z >= outer.min_m.z - slack && inner.max_m.x <= outer.max_m.x + slack &&
         inner.max_m.y <= outer.max_m.y + slack && inner.max_m.z <= outer.max_m.z + slack;
}

bool ordered(const Aabb& b) { return b.min_m.x < b.max_m.x && b.min_m.y < b.max_m.y && b.min_m.z < b.max_m.z; }

Aabb read_box(Reader& r) {
  Aabb box;
  if (auto v = r.required_vec3("min_m")) box.min_m = *v;
  if (auto v = r.required_vec3("max_m")) box.max_m = *v;
  if (r.has("min_m") && r.has("max_m"))
    r.check("max_m", ordered(box), "must be greater than min_m " + fmt(box.min_m) + " on every axis");
  return box;
}

Domain read_domain(Reader& r) {
  Domain d;
  d.box = read_box(r);
  if (auto w = r.table("walls")) {
    d.walls.floor = w->boolean("floor", true);
    d.walls.ceiling = w->boolean("ceiling", false);
    d.walls.x_min = w->boolean("x_min", true);
    d.walls.x_max = w->boolean("x_max", true);
    d.walls.y_min = w->boolean("y_min", true);
    d.walls.y_max = w->boolean("y_max", true);
    w->finish();
  }
  d.boundary_layers = static_cast<int>(r.integer("boundary_layers", d.boundary_layers));
  r.check("boundary_layers", d.boundary_layers >= 1 && d.boundary_layers <= 4, "must be 1..4");
  r.finish();
  return d;
}

Fluid read_fluid(Reader& r, const Domain& domain) {
  Fluid f;
  f.solver = r.choice<PressureSolver>("solver", PressureSolver::dfsph,
                                      {{"dfsph", PressureSolver::dfsph}, {"wcsph", PressureSolver::wcsph}});
  const bool wcsph = f.solver == PressureSolver::wcsph;
  f.rest_density_kg_m3 = r.number("rest_density_kg_m3", f.rest_density_kg_m3);
  r.check("rest_density_kg_m3", f.rest_density_kg_m3 > 0, "must be > 0");
  f.particle_spacing_m = r.required_number("particle_spacing_m");
  r.check("particle_spacing_m", f.particle_spacing_m > 0 || !r.has("particle_spacing_m"), "must be > 0");
  f.support_radius_m = r.number("support_radius_m", 0.0);
  if (r.has("support_radius_m") && f.particle_spacing_m > 0)
    r.check("support_radius_m", f.support_radius_m >= 1.2 * f.particle_spacing_m && f.support_radius_m <= 5 * f.particle_spacing_m,
            "must be 1.2..5 times particle_spacing_m (" + fmt(f.particle_spacing_m) + ")");
  f.stiffness_pa = r.number("stiffness_pa", 0.0);
  f.speed_of_sound_m_s = r.number("speed_of_sound_m_s", 0.0);
  if (r.has("stiffness_pa")) r.check("stiffness_pa", f.stiffness_pa > 0, "must be > 0");
  if (r.has("speed_of_sound_m_s")) r.check("speed_of_sound_m_s", f.speed_of_sound_m_s > 0, "must be > 0");
  if (wcsph && !r.has("stiffness_pa") && !r.has("speed_of_sound_m_s"))
    r.problem("speed_of_sound_m_s", "missing (give speed_of_sound_m_s or stiffness_pa for the pressure law, eq. 7, of solver = \"wcsph\")");
  if (r.has("stiffness_pa") && r.has("speed_of_sound_m_s"))
    r.problem("stiffness_pa", "give either stiffness_pa or speed_of_sound_m_s, not both");
  f.viscosity_pa_s = r.number("viscosity_pa_s", f.viscosity_pa_s);
  r.check("viscosity_pa_s", f.viscosity_pa_s >= 0, "must be >= 0");
  f.density_error_percent = r.number("density_error_percent", f.density_error_percent);
  r.check("density_error_percent", f.density_error_percent >= 0.001 && f.density_error_percent <= 5, "must be in [0.001, 5] %");
  f.divergence_error_percent = r.number("divergence_error_percent", f.divergence_error_percent);
  r.check("divergence_error_percent", f.divergence_error_percent >= 0.001 && f.divergence_error_percent <= 5,
          "must be in [0.001, 5] %");
  f.max_solver_iterations = static_cast<int>(r.integer("max_solver_iterations", f.max_solver_iterations));
  r.check("max_solver_iterations", f.max_solver_iterations >= 2 && f.max_solver_iterations <= 1000, "must be 2..1000");
  f.xsph_fraction = r.number("xsph_fraction", f.xsph_fraction);
  r.check("xsph_fraction", f.xsph_fraction >= 0 && f.xsph_fraction <= 0.5, "must be in [0, 0.5]");
  f.settle_s = r.number("settle_s", f.settle_s);
  r.check("settle_s", f.settle_s >= 0 && f.settle_s <= 10, "must be in [0, 10] s");
  if (wcsph)
    for (const char* key :
         {"density_error_percent", "divergence_error_percent", "max_solver_iterations", "xsph_fraction", "settle_s"})
      if (r.has(key)) r.problem(key, "applies to solver = \"dfsph\" only (this fluid uses \"wcsph\")");
  f.gravity_m_s2 = r.vec3("gravity_m_s2", f.gravity_m_s2);
  f.look = r.choice<FluidLook>("look", FluidLook::water,
                               {{"water", FluidLook::water}, {"batter", FluidLook::batter},
                                {"honey", FluidLook::honey}, {"syrup", FluidLook::syrup}});
  for (auto& b : r.tables("blocks")) {
    FluidBlock block{read_box(b), b.string("vessel", "")};
    if (b.has("min_m") && b.has("max_m") && ordered(block.box) && ordered(domain.box)) {
      b.check("max_m", inside(block.box, domain.box, 1e-9),
              "fluid block " + fmt(block.box.min_m) + ".." + fmt(block.box.max_m) + " must lie inside the domain " +
                  fmt(domain.box.min_m) + ".." + fmt(domain.box.max_m));
      const Vec3 e{block.box.max_m.x - block.box.min_m.x, block.box.max_m.y - block.box.min_m.y,
                   block.box.max_m.z - block.box.min_m.z};
      if (f.particle_spacing_m > 0)
        b.check("max_m", std::min({e.x, e.y, e.z}) >= f.particle_spacing_m,
                "fluid block is thinner than one particle spacing (" + fmt(f.particle_spacing_m) + " m)");
    }
    b.finish();
    f.blocks.push_back(block);
  }
  r.finish();
  return f;
}

TimeStepping read_time(Reader& r, PressureSolver solver) {
  TimeStepping t;
  t.cfl = solver == PressureSolver::wcsph ? TimeStepping::kDefaultCflWcsph : TimeStepping::kDefaultCflDfsph;
  t.dt_s = r.number("dt_s", 0.0);
  r.check("dt_s", t.dt_s >= 0 && t.dt_s <= 0.01, "must be 0 (CFL) or a step in (0, 0.01] s");
  t.cfl = r.number("cfl", t.cfl);  // default: TimeStepping::cfl
  r.check("cfl", t.cfl > 0 && t.cfl <= 1, "must be in (0, 1]");
  t.max_dt_s = r.number("max_dt_s", t.max_dt_s);
  r.check("max_dt_s", t.max_dt_s > 0 && t.max_dt_s <= 0.01, "must be in (0, 0.01] s");
  t.frame_rate_hz = r.number("frame_rate_hz", t.frame_rate_hz);
  r.check("frame_rate_hz", t.frame_rate_hz > 0 && t.frame_rate_hz <= 2000, "must be in (0, 2000] Hz");
  r.finish();
  return t;
}

Pose read_pose(Reader& r, const char* position_key, const char* orientation_key, bool position_required) {
  Pose p;
  if (position_required) {
    if (auto v = r.required_vec3(position_key)) p.position_m = *v;
  } else {
    p.position_m = r.vec3(position_key, p.position_m);
  }
  p.orientation = r.quaternion(orientation_key, p.orientation);
  return p;
}

Body read_body(Reader& r, const std::filesystem::path& scene_dir, const Scene& scene) {
  Body b;
  if (auto name = r.required_string("name")) b.name = *name;
  b.shape = r.choice<BodyShape>("shape", BodyShape::mesh, {{"mesh", BodyShape::mesh}, {"particle", BodyShape::particle}});
  const bool particle = b.shape == BodyShape::particle;
  std::optional<std::string> mesh;
  if (!particle) {
    mesh = r.required_string("mesh");
  } else {
    // One particle of the fluid's size: nothing to sample, scale or turn.
    if (r.has("mesh")) r.string("mesh", "");  // said once, below, not again as an unknown key
    for (const char* key : {"mesh", "scale", "sampling_spacing_m", "orientation"})
      if (r.has(key)) r.problem(key, "a particle body has no mesh: remove it (shape = \"particle\")");
  }
  b.scale = r.number("scale", 1.0);
  r.check("scale", b.scale > 0, "must be > 0");
  b.pose = read_pose(r, "position_m", "orientation", true);
  b.density_kg_m3 = r.number("density_kg_m3", 0.0);
  b.mass_kg = r.number("mass_kg", 0.0);
  b.viscosity_pa_s = r.number("viscosity_pa_s", 0.0);
  r.check("viscosity_pa_s", b.viscosity_pa_s >= 0, "must be >= 0");
  b.sampling_spacing_m = r.number("sampling_spacing_m", 0.0);
  if (r.has("sampling_spacing_m")) r.check("sampling_spacing_m", b.sampling_spacing_m > 0, "must be > 0");
  b.dynamic = r.boolean("dynamic", true);
  if (r.has("density_kg_m3")) r.check("density_kg_m3", b.density_kg_m3 > 0, "must be > 0");
  if (r.has("mass_kg")) r.check("mass_kg", b.mass_kg > 0, "must be > 0");
  if (r.has("density_kg_m3") && r.has("mass_kg")) r.problem("mass_kg", "give either density_kg_m3 or mass_kg, not both");
  if (b.dynamic && !r.has("density_kg_m3") && !r.has("mass_kg"))
    r.problem("density_kg_m3", "missing (a dynamic body needs density_kg_m3 or mass_kg)");
  if (particle) {
    r.check("dynamic", b.dynamic, "a particle body is a device's probe: it must be dynamic");
    const Aabb& domain = scene.domain.box;
    if (ordered(domain))
      r.check("position_m", inside(Aabb{b.pose.position_m, b.pose.position_m}, domain, 1e-9),
              "particle outside the domain: " + fmt(b.pose.position_m) + " must lie inside " + fmt(domain.min_m) + ".." +
                  fmt(domain.max_m));
  }

  if (mesh) {
    b.mesh = std::filesystem::path(*mesh).is_absolute() ? std::filesystem::path(*mesh) : scene_dir / *mesh;
    std::error_code ec;
    if (!std::filesystem::is_regular_file(b.mesh, ec)) {
      r.problem("mesh", "mesh file not found: " + b.mesh.lexically_normal().string());
    } else {
      try {
        TriangleMesh m = load_mesh(b.mesh);
        Aabb placed = transformed_bounds(m, b.scale, b.pose);
        const Aabb& domain = scene.domain.box;
        if (ordered(domain))
          r.check("position_m", inside(placed, domain, 1e-9),
                  "body outside the domain: its bounds " + fmt(placed.min_m) + ".." + fmt(placed.max_m) +
                      " must lie inside " + fmt(domain.min_m) + ".." + fmt(domain.max_m));
        double spacing = b.sampling_spacing_m > 0 ? b.sampling_spacing_m : scene.fluid.particle_spacing_m;
        double extent = std::max({placed.max_m.x - placed.min_m.x, placed.max_m.y - placed.min_m.y,
                                  placed.max_m.z - placed.min_m.z});
        if (spacing > 0)
          r.check(r.has("sampling_spacing_m") ? "sampling_spacing_m" : "mesh", spacing * 3 <= extent,
                  "particle spacing " + fmt(spacing) + " m is too large for this mesh (largest extent " + fmt(extent) +
                      " m): the body would be fewer than 3 particles across");
      } catch (const ConfigError& e) {
        for (const auto& p : e.problems()) r.problem("mesh", "cannot read mesh: " + p.to_string());
      }
    }
  }
  r.finish();
  return b;
}

MotionSegment read_segment(Reader& r) {
  MotionSegment s;
  s.kind = r.choice<MotionKind>("kind", MotionKind::oscillate,
                                {{"keyframes", MotionKind::keyframes}, {"oscillate", MotionKind::oscillate},
                                 {"spin", MotionKind::spin}, {"tilt", MotionKind::tilt}});
  if (!r.has("kind")) r.problem("kind", "missing (one of \"keyframes\", \"oscillate\", \"spin\", \"tilt\")");
  s.start_s = r.number("start_s", 0.0);
  r.check("start_s", s.start_s >= 0, "must be >= 0");
  s.stop_s = r.number("stop_s", 1e9);
  r.check("stop_s", s.stop_s > s.start_s, "must be after start_s");
  auto unit_axis = [&]() {
    s.axis = r.vec3("axis", s.axis);
    double n = std::sqrt(s.axis.x * s.axis.x + s.axis.y * s.axis.y + s.axis.z * s.axis.z);
    r.check("axis", n > 1e-9, "must be a non-zero vector");
    if (n > 1e-9) s.axis = {s.axis.x / n, s.axis.y / n, s.axis.z / n};
  };
  switch (s.kind) {
    case MotionKind::oscillate:
      unit_axis();
      s.amplitude_m = r.required_number("amplitude_m");
      r.check("amplitude_m", s.amplitude_m >= 0, "must be >= 0");
      s.frequency_hz = r.required_number("frequency_hz");
      r.check("frequency_hz", s.frequency_hz > 0 || !r.has("frequency_hz"), "must be > 0");
      s.ramp_s = r.number("ramp_s", 0.0);
      r.check("ramp_s", s.ramp_s >= 0 && 2 * s.ramp_s <= s.stop_s - s.start_s, "must be >= 0 and fit twice in stop_s - start_s");
      break;
    case MotionKind::spin:
      unit_axis();
      s.angular_speed_rad_s = r.required_number("angular_speed_rad_s");
      s.ramp_s = r.number("ramp_s", 0.0);
      r.check("ramp_s", s.ramp_s >= 0 && 2 * s.ramp_s <= s.stop_s - s.start_s, "must be >= 0 and fit twice in stop_s - start_s");
      s.pivot_offset_m = r.vec3("pivot_offset_m", {});
      break;
    case MotionKind::tilt:
      unit_axis();
      s.angle_rad = r.required_number("angle_rad");
      s.hold_s = r.number("hold_s", 0.0);
      r.check("hold_s", s.hold_s >= 0 && s.hold_s < s.stop_s - s.start_s, "must be >= 0 and shorter than stop_s - start_s");
      s.pivot_offset_m = r.vec3("pivot_offset_m", {});
      r.check("stop_s", r.has("stop_s"), "a tilt needs stop_s (it tilts and returns within [start_s, stop_s])");
      break;
    case MotionKind::keyframes: {
      auto frames = r.tables("keyframes");
      r.check("keyframes", frames.size() >= 2, "a keyframes motion needs at least 2 keyframes");
      double last_t = -1;
      for (auto& f : frames) {
        Keyframe k;
        k.t_s = f.required_number("t_s");
        f.check("t_s", k.t_s > last_t, "keyframe times must increase");
        last_t = k.t_s;
        k.pose = read_pose(f, "position_m", "orientation", true);
        f.finish();
        s.keyframes.push_back(k);
      }
      break;
    }
  }
  r.finish();
  return s;
}

SceneDevice read_device(Reader& r) {
  SceneDevice d;
  if (auto name = r.required_string("name")) d.name = *name;
  d.source = r.choice<DeviceSource>("source", DeviceSource::scripted,
                                    {{"scripted", DeviceSource::scripted}, {"rig", DeviceSource::rig}});
  d.rig_device = r.string("rig_device", "");
  if (d.source == DeviceSource::rig)
    r.check("rig_device", !d.rig_device.empty(), "missing (a device with source = \"rig\" names its rig device)");
  d.motion.start = read_pose(r, "start_position_m", "start_orientation", true);
  d.workspace_centre_m = r.vec3("workspace_centre_m", d.motion.start.position_m);
  for (auto& seg : r.tables("motion")) d.motion.segments.push_back(read_segment(seg));
  r.finish();
  return d;
}

Coupling read_coupling(Reader& r, const Scene& scene) {
  Coupling c;
  if (auto device = r.required_string("device")) {
    c.device = *device;
    r.check("device", scene.find_device(c.device) != nullptr,
            "coupling to a missing device \"" + c.device + "\" (no [[devices]] entry with that name)");
  }
  if (auto body = r.required_string("body")) {
    c.body = *body;
    const Body* b = scene.find_body(c.body);
    r.check("body", b != nullptr, "coupling to a missing body \"" + c.body + "\" (no [[bodies]] entry with that name)");
    if (b) r.check("body", b->dynamic, "coupling to the static body \"" + c.body + "\": a coupled body must be dynamic");
  }
  c.kind = r.choice<CouplingKind>("kind", CouplingKind::rigid, {{"rigid", CouplingKind::rigid}, {"probe", CouplingKind::probe}});
  const bool probe = c.kind == CouplingKind::probe;
  if (const Body* b = scene.find_body(c.body)) {
    const bool particle = b->shape == BodyShape::particle;
    if (probe && !particle)
      r.problem("kind", "a probe holds a particle body, and \"" + c.body +
                            "\" is a mesh: give the body shape = \"particle\", or use kind = \"rigid\"");
    if (!probe && particle)
      r.problem("kind", "\"" + c.body + "\" is a particle: hold it with kind = \"probe\" (forces only)");
  }
  if (probe) {
    // A probe is held at its centre and renders no torque: nothing to give for the angular part.
    for (const char* key : {"grasp_position_m", "grasp_orientation", "angular_stiffness_nm_per_rad",
                            "angular_damping_nm_s_per_rad"})
      if (r.has(key)) r.problem(key, "a probe renders forces only (kind = \"probe\"): remove it");
    r.number("angular_stiffness_nm_per_rad", 0), r.number("angular_damping_nm_s_per_rad", 0);  // said above
    c.angular_stiffness_nm_per_rad = 0, c.angular_damping_nm_s_per_rad = 0;
  }
  c.grasp = read_pose(r, "grasp_position_m", "grasp_orientation", false);
  auto nonneg = [&](std::string_view key, double& value) {
    value = r.number(key, value);
    r.check(key, value >= 0, "must be >= 0");
  };
  nonneg("linear_stiffness_n_per_m", c.linear_stiffness_n_per_m);
  nonneg("linear_damping_n_s_per_m", c.linear_damping_n_s_per_m);
  if (!probe) {
    nonneg("angular_stiffness_nm_per_rad", c.angular_stiffness_nm_per_rad);
    nonneg("angular_damping_nm_s_per_rad", c.angular_damping_nm_s_per_rad);
  }
  r.finish();
  return c;
}

}  // namespace

const Body* Scene::find_body(const std::string& wanted) const {
  for (const auto& b : bodies)
    if (b.name == wanted) return &b;
  return nullptr;
}

const SceneDevice* Scene::find_device(const std::string& wanted) const {
  for (const auto& d : devices)
    if (d.name == wanted) return &d;
  return nullptr;
}

Scene parse_scene(const std::string& text, const std::filesystem::path& file) {
  toml::table root = detail::parse_toml(text, file);
  detail::Diagnostics diag{file.string(), {}};
  Reader r(root, "", diag);
  Scene scene;
  scene.file = file;
  scene.name = r.string("name", file.stem().string());
  scene.description = r.string("description", "");
  scene.duration_s = r.number("duration_s", scene.duration_s);
  r.check("duration_s", scene.duration_s > 0, "must be > 0");
  if (auto d = r.table("domain")) scene.domain = read_domain(*d);
  else r.problem("domain", "missing (a [domain] table with min_m and max_m is required)");
  if (auto f = r.table("fluid")) scene.fluid = read_fluid(*f, scene.domain);
  else r.problem("fluid", "missing (a [fluid] table is required)");
  if (auto t = r.table("time")) {
    scene.time = read_time(*t, scene.fluid.solver);
  } else {
    scene.time.cfl = scene.fluid.solver == PressureSolver::wcsph ? TimeStepping::kDefaultCflWcsph : TimeStepping::kDefaultCflDfsph;
  }

  std::set<std::string> names;
  auto unique = [&](Reader& item, const std::string& name, const char* what) {
    if (!name.empty() && !names.insert(name).second)
      item.problem("name", std::string("duplicate ") + what + " name \"" + name + "\"");
  };
  const std::filesystem::path dir = file.parent_path();
  for (auto& b : r.tables("bodies")) {
    scene.bodies.push_back(read_body(b, dir, scene));
    unique(b, scene.bodies.back().name, "body");
  }
  // A block's vessel names a body, read after the fluid.
  const bool vessels = std::any_of(scene.fluid.blocks.begin(), scene.fluid.blocks.end(),
                                   [](const FluidBlock& b) { return !b.vessel.empty(); });
  if (auto f = vessels ? r.table("fluid") : std::nullopt) {
    auto blocks = f->tables("blocks");
    if (blocks.size() != scene.fluid.blocks.size()) blocks.clear();  // already reported
    const Vec3 g = scene.fluid.gravity_m_s2;
    const bool weightless = g.x == 0 && g.y == 0 && g.z == 0;
    for (std::size_t i = 0; i < blocks.size(); ++i) {
      const std::string& vessel = scene.fluid.blocks[i].vessel;
      if (vessel.empty()) continue;
      const Body* body = scene.find_body(vessel);
      if (body == nullptr)
        blocks[i].problem("vessel", "no [[bodies]] entry is named \"" + vessel + "\"");
      else if (body->shape == BodyShape::particle)
        blocks[i].problem("vessel", "body \"" + vessel + "\" is a particle; a vessel is a body with a mesh");
      if (weightless) blocks[i].problem("vessel", "needs gravity to say which way is down (fluid.gravity_m_s2 is zero)");
    }
  }
  names.clear();
  for (auto& d : r.tables("devices")) {
    scene.devices.push_back(read_device(d));
    unique(d, scene.devices.back().name, "device");
  }
  // N devices may hold one body (bimanual, §6.4.4), but a device holds one body: its wrench is
  // the reaction of a single coupling.
  std::map<std::string, std::size_t> first_coupling_of_device;
  for (auto& c : r.tables("couplings")) {
    scene.couplings.push_back(read_coupling(c, scene));
    const Coupling& added = scene.couplings.back();
    if (added.device.empty()) continue;
    const auto [held, fresh] = first_coupling_of_device.try_emplace(added.device, scene.couplings.size() - 1);
    if (fresh) continue;
    const Coupling& first = scene.couplings[held->second];
    const std::string first_name = "couplings[" + std::to_string(held->second) + "]";
    if (first.body == added.body)
      c.problem("device", "already holds body \"" + first.body + "\" (" + first_name +
                              "): one coupling per device and body; remove one of the two");
    else
      c.problem("device", "already holds body \"" + first.body + "\" (" + first_name + "): a device holds one body; give \"" +
                              added.body + "\" its own [[devices]] entry, or couple it to a device that holds nothing");
  }
  r.finish();
  diag.throw_if_any();
  return scene;
}

Scene load_scene(const std::filesystem::path& file) {
  return parse_scene(detail::read_text_file(file, "scene"), file);
}

const char* to_string(FluidLook l) {
  switch (l) {
    case FluidLook::water: return "water";
    case FluidLook::batter: return "batter";
    case FluidLook::honey: return "honey";
    case FluidLook::syrup: return "syrup";
  }
  return "?";
}
const char* to_string(PressureSolver s) { return s == PressureSolver::wcsph ? "wcsph" : "dfsph"; }
const char* to_string(DeviceSource s) { return s == DeviceSource::rig ? "rig" : "scripted"; }

}  // namespace hapfluid::config
