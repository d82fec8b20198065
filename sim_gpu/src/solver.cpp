#include "hapfluid/sim/solver.hpp"

#include <algorithm>
#include <cmath>

#include "hapfluid/sim/cpu_solver.hpp"
#include "hapfluid/sim/dfsph_solver.hpp"

namespace hapfluid::sim {

int Solver::advance(double duration_s, const std::function<void(double)>& before_substep) {
  if (duration_s <= 0) return 0;
  const double dt_max = stable_time_step();
  const int substeps = std::max(1, static_cast<int>(std::ceil(duration_s / dt_max - 1e-9)));
  const double dt = duration_s / substeps;
  const double t0 = time_s();
  for (int i = 0; i < substeps; ++i) {
    if (before_substep) before_substep(t0 + i * dt);
    step(dt);
  }
  return substeps;
}

std::unique_ptr<Solver> make_cpu_solver(SimulationModel model, int threads) {
  if (model.params.solver == config::PressureSolver::dfsph) return std::make_unique<DfsphSolver>(std::move(model), threads);
  return std::make_unique<CpuSolver>(std::move(model), threads);
}

}  // namespace hapfluid::sim
