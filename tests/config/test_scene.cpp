// Scene files: the shipped scenes (the paper's scenarios and the validation cases) load, and each
// class of mistake is reported with file, key path, value and reason.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>

#include "hapfluid/config/errors.hpp"
#include "hapfluid/config/scene.hpp"

using namespace hapfluid::config;

namespace {

// Parsed as if it lived in config/scenes/, so "../meshes/x.obj" resolves to the shipped meshes.
const std::filesystem::path kScenePath = "config/scenes/test.toml";

const std::string kBase = R"(
[domain]
min_m = [0.0, 0.0, 0.0]
max_m = [0.4, 0.3, 0.4]

[fluid]
solver = "wcsph"
particle_spacing_m = 0.02
speed_of_sound_m_s = 5.0

[[fluid.blocks]]
min_m = [0.0, 0.0, 0.0]
max_m = [0.4, 0.3, 0.08]
)";

const std::string kSpoon = R"(
[[bodies]]
name = "spoon"
mesh = "../meshes/spoon.obj"
position_m = [0.2, 0.15, 0.06]
density_kg_m3 = 700.0
sampling_spacing_m = 0.01
)";

const std::string kHand = R"(
[[devices]]
name = "hand"
start_position_m = [0.2, 0.15, 0.3]
)";

std::string problems_of(const std::string& text) {
  try {
    parse_scene(text, kScenePath);
    return "";
  } catch (const ConfigError& e) {
    return e.what();
  }
}

void expect_problem(const std::string& text, const std::string& expected) {
  std::string p = problems_of(text);
  EXPECT_NE(p.find(expected), std::string::npos) << "expected: " << expected << "\ngot: " << p;
}

}  // namespace

TEST(Scene, EveryShippedSceneLoads) {
  int count = 0;
  for (const auto& entry : std::filesystem::directory_iterator("config/scenes")) {
    SCOPED_TRACE(entry.path().string());
    EXPECT_NO_THROW(load_scene(entry.path()));
    ++count;
  }
  EXPECT_GE(count, 10);  // 8 paper scenarios (4 glasses) + validation scenes
}

TEST(Scene, PaperScenariosHaveTheirDevicesAndCouplings) {
  Scene pour = load_scene("config/scenes/bowl_pouring.toml");
  EXPECT_EQ(pour.devices.size(), 2u);
  EXPECT_EQ(pour.couplings.size(), 2u);
  Scene bucket = load_scene("config/scenes/bucket_bimanual.toml");
  ASSERT_EQ(bucket.couplings.size(), 2u);
  EXPECT_EQ(bucket.couplings[0].body, bucket.couplings[1].body);  // two hands, one body
  for (int v : {2, 10, 20, 40}) {
    Scene glass = load_scene("config/scenes/spinning_glass_" + std::to_string(v) + ".toml");
    EXPECT_DOUBLE_EQ(glass.bodies.at(0).viscosity_pa_s, v);
    EXPECT_DOUBLE_EQ(glass.fluid.viscosity_pa_s, 2.0);
  }
}

TEST(Scene, ValidSceneResolvesDefaults) {
  Scene s = parse_scene(kBase + kSpoon, kScenePath);
  EXPECT_DOUBLE_EQ(s.support_radius(), 0.04);  // 2 x spacing when not given
  EXPECT_DOUBLE_EQ(s.fluid.effective_stiffness(), 25.0);  // k = c^2
  EXPECT_TRUE(std::filesystem::exists(s.bodies.at(0).mesh));
}

TEST(Scene, NonPositiveSpacing) {
  std::string text = kBase;
  text.replace(text.find("0.02"), 4, "-0.01");
  expect_problem(text, "test.toml:8: fluid.particle_spacing_m = -0.01: must be > 0");
}

TEST(Scene, BodyOutsideTheDomain) {
  std::string text = kBase + kSpoon;
  text.replace(text.find("[0.2, 0.15, 0.06]"), 17, "[0.2, 0.29, 0.06]");  // the bowl is 0.075 m wide
  expect_problem(text, "bodies.spoon.position_m = [0.2, 0.29, 0.06]: body outside the domain");
}

TEST(Scene, MeshNotFound) {
  std::string text = kBase + kSpoon;
  text.replace(text.find("spoon.obj"), 9, "ladle.obj");
  expect_problem(text, "bodies.spoon.mesh = \"../meshes/ladle.obj\": mesh file not found");
}

TEST(Scene, SpacingTooLargeForTheMesh) {
  std::string text = kBase + kSpoon;
  text.replace(text.find("sampling_spacing_m = 0.01"), 25, "sampling_spacing_m = 0.15");
  expect_problem(text, "bodies.spoon.sampling_spacing_m = 0.15: particle spacing 0.15 m is too large for this mesh");
}

TEST(Scene, CouplingToAMissingDeviceOrBody) {
  expect_problem(kBase + kSpoon + kHand + "[[couplings]]\ndevice = \"left\"\nbody = \"spoon\"\n",
                 "couplings[0].device = \"left\": coupling to a missing device \"left\"");
  expect_problem(kBase + kSpoon + kHand + "[[couplings]]\ndevice = \"hand\"\nbody = \"ladle\"\n",
                 "couplings[0].body = \"ladle\": coupling to a missing body \"ladle\"");
}

TEST(Scene, OneDeviceHoldsOneBody) {
  // Several devices may hold one body (the bimanual bucket), but one device renders the reaction
  // of one coupling: a device coupled to a second body is refused, naming the first.
  const std::string ladle = R"(
[[bodies]]
name = "ladle"
mesh = "../meshes/spoon.obj"
position_m = [0.1, 0.15, 0.06]
density_kg_m3 = 700.0
sampling_spacing_m = 0.01
)";
  const std::string two_bodies = kBase + kSpoon + ladle + kHand +
                                 "[[couplings]]\ndevice = \"hand\"\nbody = \"spoon\"\n"
                                 "[[couplings]]\ndevice = \"hand\"\nbody = \"ladle\"\n";
  expect_problem(two_bodies, "test.toml:36: couplings[1].device = \"hand\": already holds body \"spoon\" (couplings[0]): "
                             "a device holds one body; give \"ladle\" its own [[devices]] entry, or couple it to a "
                             "device that holds nothing");
  expect_problem(kBase + kSpoon + kHand + "[[couplings]]\ndevice = \"hand\"\nbody = \"spoon\"\n"
                                           "[[couplings]]\ndevice = \"hand\"\nbody = \"spoon\"\n",
                 "couplings[1].device = \"hand\": already holds body \"spoon\" (couplings[0]): one coupling per device "
                 "and body; remove one of the two");
  // Two devices on one body, and each device on its own body, are fine.
  EXPECT_EQ(problems_of(kBase + kSpoon + ladle + kHand + "[[devices]]\nname = \"other\"\nstart_position_m = [0.1, 0.1, 0.3]\n"
                        "[[couplings]]\ndevice = \"hand\"\nbody = \"spoon\"\n"
                        "[[couplings]]\ndevice = \"other\"\nbody = \"spoon\"\n"),
            "");
  EXPECT_EQ(problems_of(kBase + kSpoon + ladle + kHand + "[[devices]]\nname = \"other\"\nstart_position_m = [0.1, 0.1, 0.3]\n"
                        "[[couplings]]\ndevice = \"hand\"\nbody = \"spoon\"\n"
                        "[[couplings]]\ndevice = \"other\"\nbody = \"ladle\"\n"),
            "");
}

TEST(Scene, CouplingToAStaticBody) {
  std::string text = kBase + kSpoon + "dynamic = false\n" + kHand + "[[couplings]]\ndevice = \"hand\"\nbody = \"spoon\"\n";
  expect_problem(text, "coupling to the static body \"spoon\"");
}

// Algorithm 1's probe: a particle body held by a probe coupling, forces only.
const std::string kProbe = R"(
[[bodies]]
name = "probe"
shape = "particle"
position_m = [0.2, 0.15, 0.05]
density_kg_m3 = 1000.0
)";

TEST(Scene, AProbeIsAParticleBodyHeldByAProbeCoupling) {
  const Scene s = parse_scene(kBase + kProbe + kHand + "[[couplings]]\ndevice = \"hand\"\nbody = \"probe\"\nkind = \"probe\"\n",
                              kScenePath);
  ASSERT_EQ(s.bodies.size(), 1u);
  EXPECT_EQ(s.bodies[0].shape, BodyShape::particle);
  EXPECT_TRUE(s.bodies[0].mesh.empty());
  ASSERT_EQ(s.couplings.size(), 1u);
  EXPECT_EQ(s.couplings[0].kind, CouplingKind::probe);
  EXPECT_EQ(s.couplings[0].angular_stiffness_nm_per_rad, 0.0);  // no torque to render
  EXPECT_EQ(s.couplings[0].angular_damping_nm_s_per_rad, 0.0);
  const Scene shipped = load_scene("config/scenes/probe_3dof.toml");
  EXPECT_EQ(shipped.couplings.at(0).kind, CouplingKind::probe);
}

TEST(Scene, AProbeAndItsParticleAreNotMixedWithMeshesAndTorques) {
  const std::string held = kHand + "[[couplings]]\ndevice = \"hand\"\nbody = \"probe\"\n";
  expect_problem(kBase + kProbe + held, "couplings[0].kind: \"probe\" is a particle: hold it with kind = \"probe\"");
  expect_problem(kBase + kSpoon + kHand + "[[couplings]]\ndevice = \"hand\"\nbody = \"spoon\"\nkind = \"probe\"\n",
                 "a probe holds a particle body, and \"spoon\" is a mesh");
  expect_problem(kBase + kProbe + held + "kind = \"probe\"\nangular_stiffness_nm_per_rad = 2.0\n",
                 "couplings[0].angular_stiffness_nm_per_rad = 2.0: a probe renders forces only");
  expect_problem(kBase + kProbe + "mesh = \"../meshes/spoon.obj\"\n" + held + "kind = \"probe\"\n",
                 "bodies.probe.mesh = \"../meshes/spoon.obj\": a particle body has no mesh");
  expect_problem(kBase + kProbe + "dynamic = false\n", "bodies.probe.dynamic = false: a particle body is a device's probe");
  expect_problem(kBase + kProbe + held + "kind = \"ball\"\n", "couplings[0].kind = \"ball\": must be one of \"rigid\", \"probe\"");
  std::string outside = kBase + kProbe;
  outside.replace(outside.find("[0.2, 0.15, 0.05]"), 17, "[0.2, 0.15, 0.55]");
  expect_problem(outside, "bodies.probe.position_m = [0.2, 0.15, 0.55]: particle outside the domain");
}

TEST(Scene, DynamicBodyNeedsDensityOrMass) {
  std::string text = kBase + kSpoon;
  text.replace(text.find("density_kg_m3 = 700.0\n"), 22, "");
  expect_problem(text, "bodies.spoon.density_kg_m3: missing (a dynamic body needs density_kg_m3 or mass_kg)");
}

TEST(Scene, MissingTablesAndFields) {
  expect_problem("name = \"x\"\n", "test.toml:1: domain: missing");
  expect_problem("name = \"x\"\n", "fluid: missing");
  std::string no_sound = kBase;
  no_sound.replace(no_sound.find("speed_of_sound_m_s = 5.0\n"), 25, "");
  expect_problem(no_sound, "fluid.speed_of_sound_m_s: missing (give speed_of_sound_m_s or stiffness_pa");
}

TEST(Scene, FluidBlockOutsideTheDomain) {
  std::string text = kBase;
  text.replace(text.find("[0.4, 0.3, 0.08]"), 16, "[0.5, 0.3, 0.08]");
  expect_problem(text, "fluid.blocks[0].max_m = [0.5, 0.3, 0.08]: fluid block [0, 0, 0]..[0.5, 0.3, 0.08] must lie inside the domain");
}

TEST(Scene, InvertedDomain) {
  std::string text = kBase;
  text.replace(text.find("[0.4, 0.3, 0.4]"), 15, "[0.4, -0.3, 0.4]");
  expect_problem(text, "domain.max_m = [0.4, -0.3, 0.4]: must be greater than min_m");
}

TEST(Scene, WrongTypesAndUnknownKeysInNestedTables) {
  expect_problem(kBase + "[time]\ncfl = \"fast\"\n", "time.cfl = \"fast\": must be a number");
  expect_problem(kBase + "[time]\nsubsteps = 4\n", "time.substeps = 4: unknown key");
  std::string bad_vector = kBase;
  bad_vector.replace(bad_vector.find("[0.4, 0.3, 0.4]"), 15, "[0.4, 0.3]");
  expect_problem(bad_vector, "domain.max_m = [0.4, 0.3]: must be an array of 3 finite numbers");
}

TEST(Scene, MotionSegmentsAreChecked) {
  std::string text = kBase + kHand +
                     "[[devices.motion]]\nkind = \"oscillate\"\naxis = [0.0, 0.0, 0.0]\namplitude_m = 0.1\nfrequency_hz = 1.0\n"
                     "start_s = 2.0\nstop_s = 1.0\n";
  expect_problem(text, "devices.hand.motion[0].axis = [0.0, 0.0, 0.0]: must be a non-zero vector");
  expect_problem(text, "devices.hand.motion[0].stop_s = 1.0: must be after start_s");
  std::string frames = kBase + kHand +
                       "[[devices.motion]]\nkind = \"keyframes\"\nkeyframes = [ { t_s = 1.0, position_m = [0.1, 0.1, 0.1] },"
                       " { t_s = 0.5, position_m = [0.2, 0.1, 0.1] } ]\n";
  expect_problem(frames, "devices.hand.motion[0].keyframes[1].t_s = 0.5: keyframe times must increase");
}

TEST(Scene, RigDeviceNeedsItsName) {
  expect_problem(kBase + kHand + "source = \"rig\"\n", "devices.hand.rig_device: missing");
}

TEST(Scene, DuplicateBodyNames) {
  expect_problem(kBase + kSpoon + kSpoon, "duplicate body name \"spoon\"");
}

TEST(Scene, WorkspaceCentreDefaultsToTheHandsStart) {
  // A live device's rig-frame origin (its workspace centre) lands where the scene's hand starts,
  // so one rig serves scenes whatever their coordinates; a scene may place it elsewhere.
  Scene s = parse_scene(kBase + kHand, kScenePath);
  EXPECT_DOUBLE_EQ(s.devices.at(0).workspace_centre_m.x, 0.2);
  EXPECT_DOUBLE_EQ(s.devices.at(0).workspace_centre_m.z, 0.3);
  Scene moved = parse_scene(kBase + kHand + "workspace_centre_m = [0.1, 0.15, 0.2]\n", kScenePath);
  EXPECT_DOUBLE_EQ(moved.devices.at(0).workspace_centre_m.x, 0.1);
  EXPECT_DOUBLE_EQ(moved.devices.at(0).workspace_centre_m.z, 0.2);
  expect_problem(kBase + kHand + "workspace_centre_m = [0.1, 0.15]\n",
                 "devices.hand.workspace_centre_m = [0.1, 0.15]: must be an array of 3 finite numbers");
}

// The pressure solver is named in the scene; its own keys are refused on the other method, so a
// tolerance that would silently do nothing is reported.
TEST(SceneFile, SolverKeyChoosesTheMethodAndItsKeysBelongToIt) {
  EXPECT_EQ(parse_scene(kBase, kScenePath).fluid.solver, PressureSolver::wcsph);
  std::string dfsph = kBase;
  dfsph.replace(dfsph.find("solver = \"wcsph\"\n"), 17, "solver = \"dfsph\"\ndensity_error_percent = 0.05\n");
  const Scene s = parse_scene(dfsph, kScenePath);
  EXPECT_EQ(s.fluid.solver, PressureSolver::dfsph);
  EXPECT_DOUBLE_EQ(s.fluid.density_error_percent, 0.05);
  EXPECT_DOUBLE_EQ(s.time.cfl, TimeStepping::kDefaultCflDfsph);
  std::string unknown = kBase;
  unknown.replace(unknown.find("solver = \"wcsph\"\n"), 17, "solver = \"sph\"\n");
  expect_problem(unknown, "fluid.solver");
  expect_problem(unknown, "\"dfsph\"");
  std::string misplaced = kBase;
  misplaced.replace(misplaced.find("[fluid]\n"), 8, "[fluid]\nxsph_fraction = 0.05\n");
  expect_problem(misplaced, "fluid.xsph_fraction = 0.05: applies to solver = \"dfsph\" only");
}

TEST(Scene, AFluidBlocksVesselMustBeAMeshBodyUnderGravity) {
  std::string text = kBase + kSpoon;
  text.replace(text.find("max_m = [0.4, 0.3, 0.08]\n"), 25, "max_m = [0.4, 0.3, 0.08]\nvessel = \"bowl\"\n");
  expect_problem(text, "fluid.blocks[0].vessel = \"bowl\": no [[bodies]] entry is named \"bowl\"");
  std::string spoon = text;
  spoon.replace(spoon.find("vessel = \"bowl\""), 15, "vessel = \"spoon\"");
  EXPECT_EQ(problems_of(spoon), "");
  std::string weightless = spoon;
  weightless.replace(weightless.find("speed_of_sound_m_s = 5.0\n"), 25,
                     "speed_of_sound_m_s = 5.0\ngravity_m_s2 = [0.0, 0.0, 0.0]\n");
  expect_problem(weightless, "fluid.blocks[0].vessel = \"spoon\": needs gravity to say which way is down");
  std::string probe = kBase + "[[bodies]]\nname = \"bead\"\nshape = \"particle\"\nposition_m = [0.2, 0.15, 0.2]\n" +
                      "density_kg_m3 = 1000.0\n";
  probe.replace(probe.find("max_m = [0.4, 0.3, 0.08]\n"), 25, "max_m = [0.4, 0.3, 0.08]\nvessel = \"bead\"\n");
  expect_problem(probe, "fluid.blocks[0].vessel = \"bead\": body \"bead\" is a particle");
}

TEST(Scene, TheIncompressibleSolverIsTheDefault) {
  std::string text = kBase;
  text.replace(text.find("solver = \"wcsph\"\n"), 17, "");
  const Scene s = parse_scene(text, kScenePath);
  EXPECT_EQ(s.fluid.solver, PressureSolver::dfsph);
  EXPECT_DOUBLE_EQ(s.time.cfl, TimeStepping::kDefaultCflDfsph);
  text.replace(text.find("speed_of_sound_m_s = 5.0\n"), 25, "");
  EXPECT_EQ(problems_of(text), "");  // no pressure law to give: the speed of sound is optional
}
