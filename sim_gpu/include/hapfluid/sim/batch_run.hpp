// Batch mode of haptic-sim: run a scene for a duration with its scripted device motion and
// write particle frames, body and coupling histories and run statistics to a folder.
#pragma once

#include <filesystem>
#include <ostream>
#include <string>

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

}  // namespace hapfluid::sim
