// Rig files: the shipped ones load, and every class of mistake is reported with the file, the
// line, the key path, the value and the reason — a rig with a wrong force limit must never start.
#include <gtest/gtest.h>

#include <filesystem>

#include "hapfluid/config/errors.hpp"
#include "hapfluid/config/rig.hpp"

using namespace hapfluid::config;

namespace {

const char* kMinimalDevice = R"(
[[devices]]
name = "left"
transport = { kind = "loopback", address = "/tmp/x.sock" }
)";

// Parses and returns the joined problem text, or "" when the rig is valid.
std::string problems_of(const std::string& text) {
  try {
    parse_rig(text, "rig.toml");
    return "";
  } catch (const ConfigError& e) {
    return e.what();
  }
}

}  // namespace

TEST(Rig, EveryShippedRigLoads) {
  int count = 0;
  for (const auto& entry : std::filesystem::directory_iterator("config/rigs")) {
    SCOPED_TRACE(entry.path().string());
    EXPECT_NO_THROW(load_rig(entry.path()));
    ++count;
  }
  EXPECT_GE(count, 3);
}

TEST(Rig, DefaultsAreSafeAndPerAxisLimitsFollowTheNormLimit) {
  Rig rig = parse_rig(std::string(kMinimalDevice) + "max_force_n = 4.0\n", "rig.toml");
  ASSERT_EQ(rig.devices.size(), 1u);
  const RigDevice& d = rig.devices[0];
  EXPECT_EQ(rig.rt.period_ns, 1'000'000);
  EXPECT_EQ(d.limits.max_force_n, 4.0);
  EXPECT_EQ(d.limits.max_force_axis_n.z, 4.0);
  EXPECT_EQ(d.wrench_mode, WrenchMode::interpolate);
  EXPECT_GT(d.watchdogs.sim_stale_ms, 0.0);
}

TEST(Rig, NonPositiveLimitNamesFileLineKeyValueAndReason) {
  std::string text = std::string(kMinimalDevice) + "max_force_n = -3\n";
  EXPECT_EQ(problems_of(text), "rig.toml:5: devices.left.max_force_n = -3: must be > 0");
}

TEST(Rig, LimitsBeyondTheWiresFullScaleAreRejected) {
  // The COMMAND carries +-32.767 N and +-3.2767 N*m per axis: a rig promising 40 N could never
  // send it (the encoder refuses, and a disabled zero wrench goes instead). INFO carries 1..255 ms.
  EXPECT_EQ(problems_of(std::string(kMinimalDevice) + "max_force_n = 40\n"),
            "rig.toml:5: devices.left.max_force_n = 40: must be <= 32.767 N, the full scale of the wire "
            "(firmware_bridge/protocol.md 1.2)");
  EXPECT_EQ(problems_of(std::string(kMinimalDevice) + "max_torque_nm = 3.3\n"),
            "rig.toml:5: devices.left.max_torque_nm = 3.3: must be <= 3.2767 N*m, the full scale of the wire "
            "(firmware_bridge/protocol.md 1.2)");
  EXPECT_NE(problems_of(std::string(kMinimalDevice) + "max_force_axis_n = [10, 33, 10]\n")
                .find("devices.left.max_force_axis_n = [10, 33, 10]: every component must be <= 32.767 N"),
            std::string::npos);
  EXPECT_NE(problems_of(std::string(kMinimalDevice) + "device_watchdog_ms = 300\n")
                .find("devices.left.device_watchdog_ms = 300: must be <= 255 ms"),
            std::string::npos);
  EXPECT_EQ(problems_of(std::string(kMinimalDevice) + "max_force_n = 32.767\nmax_torque_nm = 3.2767\n"), "");
}

TEST(Rig, UnknownKeyIsReportedAsATypo) {
  std::string text = std::string(kMinimalDevice) + "max_forse_n = 3.0\n";
  EXPECT_EQ(problems_of(text), "rig.toml:5: devices.left.max_forse_n = 3.0: unknown key");
}

TEST(Rig, TheDashboardListensOnLoopbackUnlessTheRigSaysWhere) {
  EXPECT_EQ(parse_rig(kMinimalDevice, "rig.toml").dashboard.address, "127.0.0.1:8642");
  const Rig rig = parse_rig(std::string("[dashboard]\naddress = \"0.0.0.0:9000\"\n") + kMinimalDevice, "rig.toml");
  EXPECT_EQ(rig.dashboard.address, "0.0.0.0:9000");
  EXPECT_EQ(problems_of(std::string("[dashboard]\naddress = \"localhost\"\n") + kMinimalDevice),
            "rig.toml:2: dashboard.address = \"localhost\": \"localhost\" is not HOST:PORT (e.g. \"127.0.0.1:8642\")");
  EXPECT_NE(problems_of(std::string("[dashboard]\naddress = \"h:70000\"\n") + kMinimalDevice).find("is not HOST:PORT"),
            std::string::npos);
  EXPECT_NE(problems_of(std::string("[dashboard]\nport = 1\n") + kMinimalDevice).find("dashboard.port = 1: unknown key"),
            std::string::npos);
}

TEST(Rig, WrongTypeIsReported) {
  std::string text = std::string(kMinimalDevice) + "max_force_n = \"ten\"\n";
  EXPECT_NE(problems_of(text).find("devices.left.max_force_n = \"ten\": must be a number"), std::string::npos);
}

TEST(Rig, NonFiniteLimitIsRejected) {
  std::string text = std::string(kMinimalDevice) + "max_torque_nm = nan\n";
  EXPECT_NE(problems_of(text).find("devices.left.max_torque_nm = nan: must be finite"), std::string::npos);
}

TEST(Rig, MissingFieldsAreReported) {
  EXPECT_NE(problems_of("[rt]\npriority = 50\n").find("devices: missing"), std::string::npos);
  std::string no_transport = problems_of("[[devices]]\nname = \"a\"\n");
  EXPECT_NE(no_transport.find("devices.a.transport: missing"), std::string::npos);
  std::string no_address = problems_of("[[devices]]\nname = \"a\"\ntransport = { kind = \"socketcan\" }\n");
  EXPECT_NE(no_address.find("devices.a.transport.address: missing"), std::string::npos);
}

TEST(Rig, BadChoicesListTheAllowedValues) {
  std::string text = "[[devices]]\nname = \"a\"\ntransport = { kind = \"serial\", address = \"x\" }\n";
  EXPECT_NE(problems_of(text).find(
                "devices.a.transport.kind = \"serial\": must be one of \"loopback\", \"socketcan\", \"hid\", \"usb_bulk\""),
            std::string::npos);
}

TEST(Rig, RtSettingsAreRangeChecked) {
  std::string text = std::string("[rt]\npriority = 120\nperiod_ns = 10\ntrace_ring_records = 1000\n") + kMinimalDevice;
  std::string p = problems_of(text);
  EXPECT_NE(p.find("rt.priority = 120: must be a SCHED_FIFO priority 1..99"), std::string::npos);
  EXPECT_NE(p.find("rt.period_ns = 10:"), std::string::npos);
  EXPECT_NE(p.find("rt.trace_ring_records = 1000: must be a power of two"), std::string::npos);
}

TEST(Rig, DuplicateDeviceNamesAreRejected) {
  std::string p = problems_of(std::string(kMinimalDevice) + kMinimalDevice);
  EXPECT_NE(p.find("duplicate device name \"left\""), std::string::npos);
}

TEST(Rig, UsbAddressMustBeVidPid) {
  std::string p = problems_of("[[devices]]\nname = \"a\"\ntransport = { kind = \"usb_bulk\", address = \"arm\" }\n");
  EXPECT_NE(p.find("devices.a.transport.address = \"arm\": must be \"vid:pid\""), std::string::npos);
}

TEST(Rig, SpaceMouseMustBeHid) {
  std::string p = problems_of("[[devices]]\nname = \"m\"\nkind = \"spacemouse\"\ntransport = { kind = \"socketcan\", address = \"can0\" }\n");
  EXPECT_NE(p.find("devices.m.kind"), std::string::npos);
}

TEST(Rig, SyntaxErrorNamesTheLine) {
  std::string p = problems_of("name = \"x\"\n[[devices]\n");
  EXPECT_NE(p.find("rig.toml:2: TOML syntax error"), std::string::npos) << p;
}

TEST(Rig, AllProblemsAreReportedAtOnce) {
  std::string text = std::string(kMinimalDevice) + "max_force_n = -1\nmax_torque_nm = -1\nbogus = 1\n";
  try {
    parse_rig(text, "rig.toml");
    FAIL() << "expected ConfigError";
  } catch (const ConfigError& e) {
    EXPECT_EQ(e.problems().size(), 3u);
  }
}

TEST(Rig, MissingFileIsAClearError) {
  try {
    load_rig("config/rigs/does_not_exist.toml");
    FAIL();
  } catch (const ConfigError& e) {
    EXPECT_NE(std::string(e.what()).find("does_not_exist.toml: cannot open rig file"), std::string::npos);
  }
}

TEST(Rig, PassivityAndRecoverySettingsAreReadAndChecked) {
  Rig rig = parse_rig(std::string(kMinimalDevice) +
                          "link_recover_ms = 250\nengage_threshold_nm = 0.02\n"
                          "passivity = { enabled = false, max_damping_n_s_per_m = 15.0 }\n",
                      "rig.toml");
  const RigDevice& d = rig.devices[0];
  EXPECT_EQ(d.watchdogs.link_recover_ms, 250.0);
  EXPECT_EQ(d.watchdogs.engage_threshold_nm, 0.02);
  EXPECT_FALSE(d.passivity.enabled);
  EXPECT_EQ(d.passivity.max_damping_n_s_per_m, 15.0);
  EXPECT_EQ(d.passivity.energy_cap_j, 0.2);
  EXPECT_NE(problems_of(std::string(kMinimalDevice) + "passivity = { energy_cap_j = 0 }\n")
                .find("devices.left.passivity.energy_cap_j = 0: must be > 0"),
            std::string::npos);
}
