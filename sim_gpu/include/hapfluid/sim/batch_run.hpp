// Batch mode of haptic-sim: run a scene for a duration with its scripted device motion and
// write particle frames, body and coupling histories and run statistics to a folder.
#pragma once

#include <filesystem>
#include <functional>
#include <memory>
#include <ostream>
#include <string>

#include "hapfluid/config/json_output.hpp"
#include "hapfluid/sim/model.hpp"
#include "hapfluid/sim/solver.hpp"

namespace hapfluid::sim {

struct BatchOptions {
  std::filesystem::path scene;
  std::string backend = "cpu";
  double duration_s = 0;         // 0: the scene's duration_s
  std::filesystem::path out;
  int threads = 1;
  double export_every_s = 0.05;  // particle frames; 0: none
  bool progress_line = false;    // a \r progress line (terminal) instead of occasional lines
};

struct BatchResult {
  std::uint64_t steps = 0;
  double simulated_time_s = 0;
  double wall_time_s = 0;
  int frames_exported = 0;
};

// Throws std::runtime_error (or config::ConfigError) with a message naming what was wrong.
// A scene that fails to load or build throws before the output folder is touched (a previous
// run there stays complete). Then the previous run's outputs are removed (stats.json first);
// a failure from there on leaves stats.json with "complete": false and the error, and the CSV
// files as .part.
BatchResult run_batch(const BatchOptions& options, std::ostream& progress);

// The same run on the solver `make_solver` builds from the scene's model (any backend);
// `extra_stats`, when given, adds the backend's own keys to stats.json. The substeps of a frame
// go to Solver::advance whole when no hand is coupled (one submission on a GPU).
using SolverFactory = std::function<std::unique_ptr<Solver>(SimulationModel)>;
using ExtraStats = std::function<void(const Solver&, config::Json&)>;
BatchResult run_batch_with(const BatchOptions& options, std::ostream& progress, const SolverFactory& make_solver,
                           const ExtraStats& extra_stats = {});

}  // namespace hapfluid::sim
