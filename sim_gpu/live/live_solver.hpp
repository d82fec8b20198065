// What the live loop needs from a simulation backend (CpuSolver or vulkan::VulkanSolver), so
// that one loop (live_runner.cpp) does the shm publishing, wall-clock following, device
// matching, CSVs and stats for both.
//
// Per step the loop sets device poses, steps, and reads bodies and couplings from model(): both
// backends keep those on the host (the Vulkan backend integrates the bodies on the host between
// its two submissions, vulkan_solver.hpp). Fluid particles live on the device with Vulkan; they
// come back only at the frame rate, in sync_and_check_finite().
#pragma once

#include <cstdint>
#include <memory>
#include <string>

#include "hapfluid/sim/cpu_solver.hpp"
#include "hapfluid/sim/model.hpp"

namespace hapfluid::sim {

// The device a backend computes on, as stats.json and the start line name it.
struct ComputeDevice {
  std::string name;    // "llvmpipe (LLVM 15.0.6, 256 bits)", "2 CPU threads"
  std::string type;    // "CPU", "discrete GPU", ... ; "host" for the cpu backend
  std::string driver;  // "llvmpipe Mesa 22.3.6 (LLVM 15.0.6)"; empty for the cpu backend
};

class LiveSolver {
 public:
  virtual ~LiveSolver() = default;

  // Bodies and couplings are current after every step; fluid particles after
  // sync_and_check_finite().
  virtual const SimulationModel& model() const = 0;
  virtual double time_s() const = 0;
  virtual std::uint64_t steps() const = 0;
  virtual void set_device_state(std::size_t device, const DeviceState& state) = 0;
  virtual double stable_time_step() const = 0;
  virtual void step(double dt) = 0;
  // Brings the fluid particles of model() up to date (a read-back on Vulkan) and throws
  // std::runtime_error naming the first non-finite particle or body.
  virtual void sync_and_check_finite() = 0;

  virtual const char* backend() const = 0;  // "cpu" or "vulkan"
  virtual ComputeDevice device() const = 0;
  virtual int threads() const = 0;  // CPU worker threads (0 on Vulkan: the driver's own)
};

class CpuLiveSolver final : public LiveSolver {
 public:
  CpuLiveSolver(SimulationModel model, int threads) : solver_(std::move(model), threads) {}
  const SimulationModel& model() const override { return solver_.model(); }
  double time_s() const override { return solver_.time_s(); }
  std::uint64_t steps() const override { return solver_.steps(); }
  void set_device_state(std::size_t device, const DeviceState& state) override { solver_.set_device_state(device, state); }
  double stable_time_step() const override { return solver_.stable_time_step(); }
  void step(double dt) override { solver_.step(dt); }
  void sync_and_check_finite() override { solver_.check_finite(); }
  const char* backend() const override { return "cpu"; }
  ComputeDevice device() const override {
    const int n = solver_.threads();
    return {std::to_string(n) + (n == 1 ? " CPU thread" : " CPU threads"), "host", ""};
  }
  int threads() const override { return solver_.threads(); }

 private:
  CpuSolver solver_;
};

}  // namespace hapfluid::sim
