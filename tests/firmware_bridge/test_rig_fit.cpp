// A rig is checked against the INFO reply of the device it connects to: the rig's limits must be
// ones the device can honour, or haptic-rt refuses to start (open_device throws, exit 2).
#include <gtest/gtest.h>

#include <unistd.h>

#include <atomic>
#include <cstring>
#include <thread>

#include "fake_firmware.hpp"
#include "hapfluid/device/loopback.hpp"
#include "hapfluid/device/open_device.hpp"
#include "hapfluid/device/rig_fit.hpp"
#include "hapfluid/device/transport.hpp"

namespace {

using namespace hapfluid;

config::RigDevice rig_device(double max_force_n, double max_torque_nm, double watchdog_ms) {
  config::RigDevice d;
  d.name = "left";
  d.limits.max_force_n = max_force_n;
  d.limits.max_torque_nm = max_torque_nm;
  d.watchdogs.device_watchdog_ms = watchdog_ms;
  return d;
}

// The INFO the emulated firmware sends for motor limits 10 N, 0.5 N*m and a 20 ms watchdog.
hf_info device_info(double max_force_n = 10.0, double max_torque_nm = 0.5, int watchdog_ms = 20) {
  fake::DeviceModel model;
  model.max_force_n = max_force_n;
  model.max_torque_nm = max_torque_nm;
  model.watchdog_ms = watchdog_ms;
  return fake::FakeFirmware(model, config::Pose{}).info();
}

}  // namespace

TEST(RigFit, ARigWithinTheDevicesLimitsAndWatchdogFits) {
  EXPECT_EQ(device::rig_beyond_device(rig_device(10.0, 0.5, 20), device_info()), "");
  EXPECT_EQ(device::rig_beyond_device(rig_device(6.0, 0.3, 50), device_info()), "")
      << "lower limits and a rig watchdog longer than the device's are safe";
}

TEST(RigFit, AForceLimitAboveTheMotorsIsRefusedNamingTheKeyBothValuesAndTheFix) {
  // 12 N asked of 10 N motors: the device would saturate, and the rig's limit would be a fiction.
  EXPECT_EQ(device::rig_beyond_device(rig_device(12.0, 0.5, 20), device_info()),
            "rig devices.left.max_force_n = 12 N is above the device's motor limit of 10 N (its INFO reply): "
            "lower it to 10");
}

TEST(RigFit, ATorqueLimitAboveTheMotorsIsRefused) {
  EXPECT_NE(device::rig_beyond_device(rig_device(10.0, 0.8, 20), device_info()).find("max_torque_nm = 0.8 N*m"),
            std::string::npos);
}

TEST(RigFit, OneInfoStepOfRoundingDownIsNotAMisfit) {
  // INFO carries 10 mN steps, rounded down: a device of 8.005 N reports 8.00 N, and the rig that
  // configured it (the fake device takes its limits from the rig) still fits.
  EXPECT_EQ(device::rig_beyond_device(rig_device(8.005, 0.5, 20), device_info(8.005)), "");
  EXPECT_NE(device::rig_beyond_device(rig_device(8.02, 0.5, 20), device_info(8.005)), "");
}

TEST(RigFit, ADeviceWatchdogLongerThanTheRigsIsRefused) {
  // The rig's reaction time to a link loss is device_watchdog_ms; a 50 ms device would keep its
  // motors on 30 ms longer than that.
  std::string misfit = device::rig_beyond_device(rig_device(10.0, 0.5, 20), device_info(10.0, 0.5, 50));
  EXPECT_NE(misfit.find("command watchdog is 50 ms"), std::string::npos) << misfit;
  EXPECT_NE(misfit.find("devices.left.device_watchdog_ms = 20"), std::string::npos) << misfit;
}

TEST(RigFit, OpenDeviceRefusesARigThatAsksMoreThanTheDeviceAnsweredWith) {
  // End to end over the loopback bus: the device answers INFO_REQUEST with 10 N motors, the rig
  // asks 12 N, and open_device throws (haptic-rt exits 2 with this message) instead of running.
  config::RigDevice d = rig_device(12.0, 0.5, 20);
  d.transport.kind = config::TransportKind::loopback;
  d.transport.address = "/tmp/hapfluid-test-rigfit-" + std::to_string(::getpid()) + ".sock";
  d.transport.framing = "hid";
  auto bus = device::open_link(d.transport, device::Side::device);
  std::atomic<bool> done{false};
  std::thread answer([&] {
    while (!done) {
      hf_message m;
      for (int budget = device::kDrainUnitBudget; bus->receive(m, budget) == device::Io::ok;)
        if (m.type == HF_MSG_INFO_REQUEST) {
          std::memset(&m, 0, sizeof m);
          m.type = HF_MSG_INFO;
          m.body.info = device_info();
          bus->send(m);
        }
      device::wait_readable(bus->transport(), 5);
    }
  });
  try {
    device::open_device(d);
    ADD_FAILURE() << "a rig asking 12 N of 10 N motors opened";
  } catch (const device::TransportError& e) {
    EXPECT_NE(std::string(e.what()).find("devices.left.max_force_n = 12 N is above the device's motor limit of 10 N"),
              std::string::npos)
        << e.what();
  }
  done = true;
  answer.join();
}
