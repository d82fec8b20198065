// The two wrench renderers (rt_core/include/hapfluid/rt/wrench_render.hpp) and the workspace
// mapping: a 70 Hz sim stream rendered at 1 kHz, and the coupling model against device motion.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>

#include "hapfluid/rt/wrench_render.hpp"
#include "hapfluid/safety/flags.hpp"

using namespace hapfluid;
using namespace hapfluid::rt;
using safety::norm;

namespace {
constexpr std::uint64_t kTickNs = 1'000'000;
constexpr double kSimHz = 70.0;

// Runs a 1 kHz loop over `seconds`; a sample of signal(t_publish) becomes visible at the first
// tick at or after its publish time, as in haptic-rt. Returns the output per tick.
template <class Signal>
std::vector<double> render_stream(Signal signal, double seconds, std::vector<double>* inputs_seen = nullptr) {
  InterpolatingRenderer r;
  std::vector<double> out;
  int next_sample = 0;
  for (std::uint64_t tick = 0; tick < std::uint64_t(seconds * 1000); ++tick) {
    std::uint64_t now = tick * kTickNs;
    std::uint64_t publish = std::uint64_t(next_sample * 1e9 / kSimHz);
    if (publish <= now) {
      double value = signal(next_sample / kSimHz);
      r.on_sample({{value, 0, 0}, {}}, now);
      if (inputs_seen) inputs_seen->push_back(value);
      ++next_sample;
    }
    out.push_back(r.render(now).force_n.x);
  }
  return out;
}
}  // namespace

TEST(InterpolateMode, SeventyHertzSineIsContinuousAtOneKilohertzAndStaysInRange) {
  // A 2 Hz, 5 N sine sampled at 70 Hz: consecutive samples differ by at most 5*2*pi*2/70 = 0.9 N.
  // Rendered at 1 kHz the output moves in ~14 steps per sample, so no tick-to-tick change may
  // exceed 0.9 N / 10; and it never leaves the range of the samples (no overshoot).
  std::vector<double> inputs;
  auto out = render_stream([](double t) { return 5.0 * std::sin(2 * M_PI * 2 * t); }, 2.0, &inputs);
  double max_sample_step = 0;
  for (std::size_t i = 1; i < inputs.size(); ++i) max_sample_step = std::max(max_sample_step, std::abs(inputs[i] - inputs[i - 1]));
  double lo = *std::min_element(inputs.begin(), inputs.end());
  double hi = *std::max_element(inputs.begin(), inputs.end());
  for (std::size_t k = 1; k < out.size(); ++k) {
    EXPECT_LE(std::abs(out[k] - out[k - 1]), max_sample_step / 10.0) << "tick " << k;
    EXPECT_GE(out[k], lo - 1e-12);
    EXPECT_LE(out[k], hi + 1e-12);
  }
}

TEST(InterpolateMode, StepIsFollowedWithoutOvershootWithinOneSamplePeriod) {
  // A 0 -> 4 N step in the sim stream: the output rises monotonically, never above 4 N, and
  // reaches 4 N within one sample period (1/70 s = 14.3 ms) plus a tick of the step's arrival.
  auto out = render_stream([](double t) { return t >= 0.5 ? 4.0 : 0.0; }, 1.0);
  int arrival = static_cast<int>(std::ceil(std::ceil(0.5 * kSimHz) / kSimHz * 1000));
  int reached = -1;
  for (std::size_t k = 1; k < out.size(); ++k) {
    EXPECT_LE(out[k], 4.0 + 1e-12);
    EXPECT_GE(out[k], out[k - 1] - 1e-12) << "monotone";
    if (reached < 0 && out[k] >= 4.0 - 1e-9) reached = static_cast<int>(k);
  }
  ASSERT_GE(reached, 0);
  EXPECT_LE(reached - arrival, 15 + 1) << "delay bounded by one sample period (+1 tick)";
  EXPECT_GE(reached - arrival, 10) << "interpolated, not jumped";
}

TEST(InterpolateMode, DelayIsAboutOneSamplePeriod) {
  // Against a slow ramp the output tracks the input delayed by ~one sample period (14 ms) + half.
  auto signal = [](double t) { return 10.0 * t; };  // 10 N/s
  auto out = render_stream(signal, 1.0);
  for (int k = 300; k < 1000; k += 50) {
    double lag_s = (signal(k * 1e-3) - out[k]) / 10.0;
    EXPECT_GT(lag_s, 0.005);
    EXPECT_LT(lag_s, 0.030) << "tick " << k;
  }
}

namespace {
shm::CouplingModel model_at_origin(double k, double d) {
  shm::CouplingModel m{};
  m.valid = 1;
  m.force_n[2] = 1.0;  // F0 = 1 N up at x0 = 0
  m.q0[0] = 1;
  m.stiffness_n_per_m = k;
  m.damping_n_s_per_m = d;
  m.angular_stiffness_nm_per_rad = 2.0;
  m.angular_damping_nm_s_per_rad = 0.0;
  return m;
}
const CouplingCaps kCaps{2000.0, 5.0, 20.0, 0.2};  // N/m, N*m/rad, N*s/m, N*m*s/rad
}  // namespace

TEST(CouplingMode, DeviceStepChangesTheWrenchOnTheVeryNextTick) {
  // The whole point of the local model: a 1 mm push of the handle along +x against a 500 N/m
  // coupling is felt as -0.5 N at once, not a sim period later.
  auto m = model_at_origin(500, 0);
  Twist6 at_rest{};
  std::uint32_t capped = 0;
  EXPECT_NEAR(render_coupling(m, at_rest, kCaps, 0.0, capped).force_n.z, 1.0, 1e-12);
  Twist6 pushed = at_rest;
  pushed.position_m.x = 0.001;
  Wrench w = render_coupling(m, pushed, kCaps, 0.0, capped);
  EXPECT_NEAR(w.force_n.x, -0.5, 1e-12) << "the spring opposes the displacement";
  EXPECT_NEAR(w.force_n.z, 1.0, 1e-12);
  EXPECT_EQ(capped, 0u);
}

TEST(CouplingMode, DampingOpposesRelativeVelocityAndTorqueOpposesRotation) {
  auto m = model_at_origin(0, 4.0);
  Twist6 moving{};
  moving.linear_velocity_m_s = {0, 0.1, 0};
  moving.orientation = safety::Quat{std::cos(0.05), 0, 0, std::sin(0.05)};  // 0.1 rad about z
  std::uint32_t capped = 0;
  Wrench w = render_coupling(m, moving, kCaps, 0.0, capped);
  EXPECT_NEAR(w.force_n.y, -0.4, 1e-12);
  EXPECT_NEAR(w.torque_nm.z, -0.2, 1e-9);  // -2 N*m/rad * 0.1 rad
}

TEST(CouplingMode, StiffnessIsCappedAndNegativeGainsAreRefused) {
  // A sim asking for 1e6 N/m gets the rig's maximum closed-loop stiffness (2000 N/m); a negative
  // stiffness (an energy source) is rendered as none.
  auto m = model_at_origin(1e6, -10);
  Twist6 pushed{};
  pushed.position_m.x = 0.001;
  pushed.linear_velocity_m_s.x = 1.0;
  std::uint32_t capped = 0;
  Wrench w = render_coupling(m, pushed, kCaps, 0.0, capped);
  EXPECT_NEAR(w.force_n.x, -2.0, 1e-12);
  EXPECT_EQ(capped, safety::flag_stiffness_capped);
  m.stiffness_n_per_m = -500;
  m.damping_n_s_per_m = 0;
  EXPECT_NEAR(render_coupling(m, pushed, kCaps, 0.0, capped).force_n.x, 0.0, 1e-12);
}

TEST(CouplingMode, DampingIsCappedLikeStiffness) {
  // A sim asking for 1000 N*s/m would turn the handle's velocity noise into force noise and, sampled
  // at 1 kHz, a damper that pushes back harder than the arm's mass can follow; it gets the rig's
  // 20 N*s/m. Moving at 0.1 m/s along +y: -2 N, not -100 N. Dr likewise: 0.2 N*m*s/rad at 1 rad/s.
  auto m = model_at_origin(0, 1000.0);
  m.angular_stiffness_nm_per_rad = 0;
  m.angular_damping_nm_s_per_rad = 50.0;
  Twist6 moving{};
  moving.linear_velocity_m_s = {0, 0.1, 0};
  moving.angular_velocity_rad_s = {1.0, 0, 0};
  std::uint32_t capped = 0;
  Wrench w = render_coupling(m, moving, kCaps, 0.0, capped);
  EXPECT_NEAR(w.force_n.y, -2.0, 1e-12);
  EXPECT_NEAR(w.torque_nm.x, -0.2, 1e-12);
  EXPECT_EQ(capped, safety::flag_damping_capped) << "damping, not stiffness, was capped";
}

TEST(CouplingMode, TheAnchorMovesOnWithTheGraspBetweenSamples) {
  // A glass spun at 6.283 rad/s about z, carried along by the hand: 5 ms after the pose x0/q0
  // the hand has turned 31.4 mrad further and its grip moved 1 mm along +x at 0.2 m/s. The sim's
  // grasp moved with it (vref, wref), so the hand feels F0/tau0, not K v h = 0.5 N and
  // Kr w h = 62.8 mN*m of drag that only the sample's age made.
  auto m = model_at_origin(500, 0);
  m.torque_nm[2] = 0.004;
  m.vref_m_s[0] = 0.2;
  m.wref_rad_s[2] = 6.283;
  const double h = 0.005, angle = 6.283 * h;
  Twist6 carried{};
  carried.position_m.x = 0.2 * h;
  carried.orientation = safety::Quat{std::cos(angle / 2), 0, 0, std::sin(angle / 2)};
  std::uint32_t capped = 0;
  Wrench w = render_coupling(m, carried, kCaps, h, capped);
  EXPECT_NEAR(w.force_n.x, 0.0, 1e-12);
  EXPECT_NEAR(w.force_n.z, 1.0, 1e-12);
  EXPECT_NEAR(w.torque_nm.z, 0.004, 1e-12);
  // The same hand against a grasp the sim holds still (a body stopped at a wall): the whole
  // stretch is felt, at once.
  m.vref_m_s[0] = 0, m.wref_rad_s[2] = 0;
  w = render_coupling(m, carried, kCaps, h, capped);
  EXPECT_NEAR(w.force_n.x, -500 * 0.2 * h, 1e-12);
  EXPECT_NEAR(w.torque_nm.z, 0.004 - 2.0 * angle, 1e-12);
  // At age 0 the anchor is x0/q0 whatever its twist: the model the sim solved for.
  m.vref_m_s[0] = 0.2, m.wref_rad_s[2] = 6.283;
  EXPECT_NEAR(render_coupling(m, Twist6{}, kCaps, 0.0, capped).torque_nm.z, 0.004, 1e-12);
  // Before the pose x0 (the sim moved the pose it read on by its step): the anchor is behind x0.
  EXPECT_NEAR(render_coupling(m, Twist6{}, kCaps, -0.005, capped).force_n.x, -500 * 0.2 * 0.005, 1e-12);
  // A non-finite age is no age.
  for (double bad : {double(NAN), double(INFINITY)})
    EXPECT_NEAR(render_coupling(m, Twist6{}, kCaps, bad, capped).force_n.x, 0.0, 1e-12) << bad;
  // A half turn in the anchor: the rotation is composed exactly, not added as a small angle.
  m.wref_rad_s[2] = 3.0;
  Twist6 turned{};
  turned.orientation = safety::Quat{std::cos(0.75), 0, 0, std::sin(0.75)};  // 1.5 rad
  EXPECT_NEAR(render_coupling(m, turned, kCaps, 0.5, capped).torque_nm.z, 0.004, 1e-12);
}

TEST(CouplingMode, ANonFiniteAnchorTwistGivesANonFiniteWrenchForTheSafetyLayerToZero) {
  // The safety layer zeroes a non-finite command and flags it; an anchor rate that is NaN or
  // infinite must reach it as such, not be normalised into "no rotation".
  for (int field = 0; field < 2; ++field)
    for (double bad : {double(NAN), double(INFINITY)}) {
      auto m = model_at_origin(500, 0);
      (field == 0 ? m.vref_m_s : m.wref_rad_s)[1] = bad;
      std::uint32_t capped = 0;
      EXPECT_FALSE(safety::finite(render_coupling(m, Twist6{}, kCaps, 0.005, capped))) << field << " " << bad;
    }
}

TEST(Workspace, MappingScalesAndRotatesPosesAndWrenchesConsistently) {
  config::WorkspaceMapping mapping;
  mapping.offset_m = {0, 0, 0.1};
  mapping.scale = 2.0;
  mapping.rotation = {std::cos(M_PI / 4), 0, 0, std::sin(M_PI / 4)};  // 90 degrees about z
  mapping.force_scale = 0.5;
  Workspace ws(mapping);
  Twist6 device{};
  device.position_m = {0.01, 0, 0};
  device.linear_velocity_m_s = {1, 0, 0};
  Twist6 scene = ws.to_scene(device);
  EXPECT_NEAR(scene.position_m.y, 0.02, 1e-12);
  EXPECT_NEAR(scene.position_m.z, 0.1, 1e-12);
  EXPECT_NEAR(scene.linear_velocity_m_s.y, 2.0, 1e-12);
  Wrench device_wrench = ws.to_device({{0, 4, 0}, {}});
  EXPECT_NEAR(device_wrench.force_n.x, 2.0, 1e-12);
  EXPECT_NEAR(ws.to_scene(device_wrench).force_n.y, 4.0, 1e-12);
  EXPECT_DOUBLE_EQ(ws.linear_gain(), 1.0);
}
