// A one-device rig for the loop's unit tests. The test hands the loop its own Device, so the
// loopback transport named here is never opened; the shm prefix is private to the test process.
#pragma once

#include <unistd.h>

#include <memory>
#include <string>
#include <vector>

#include "hapfluid/config/rig.hpp"
#include "hapfluid/rt/loop.hpp"

namespace hapfluid::rt_test {

inline config::Rig one_device_rig(const std::string& device_name, const std::string& tag,
                                  int trace_ring_records = 1024) {
  config::Rig rig = config::parse_rig("[rt]\ntrace_ring_records = " + std::to_string(trace_ring_records) +
                                          "\n[[devices]]\nname = \"" + device_name +
                                          "\"\n[devices.transport]\nkind = \"loopback\"\naddress = \"/tmp/unused\"\n",
                                      tag + ".toml");
  rig.rt.shm.prefix = "hapfluid-" + tag + "-" + std::to_string(::getpid());
  return rig;
}

// The loop of `rig` driving the one device the test hands it.
inline std::unique_ptr<rt::RtLoop> one_device_loop(const config::Rig& rig, std::unique_ptr<device::Device> device) {
  std::vector<std::unique_ptr<device::Device>> devices;
  devices.push_back(std::move(device));
  return std::make_unique<rt::RtLoop>(rig, std::move(devices));
}

// The sim's side of the rig's sim_samples channel, with the attachment a loop is offered.
struct TestSim {
  shm::LatestWriter writer;
  rt::SimAttachment attachment;
};
inline std::unique_ptr<TestSim> test_sim(const config::Rig& rig) {
  const std::string name = shm::segment_name(rig.rt.shm.prefix, shm::ChannelKind::sim_samples);
  auto writer = shm::LatestWriter::create(name, shm::ChannelKind::sim_samples, sizeof(shm::SimSample));
  auto reader = shm::LatestReader::attach(name, shm::ChannelKind::sim_samples, sizeof(shm::SimSample));
  return std::make_unique<TestSim>(TestSim{std::move(writer), rt::SimAttachment{std::move(reader), 1}});
}

}  // namespace hapfluid::rt_test
