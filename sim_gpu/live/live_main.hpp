// Command line of `haptic-sim --live` (the only hook in haptic_sim_main.cpp).
#pragma once

namespace hapfluid::sim {

// True when argv holds --live.
bool wants_live(int argc, char** argv);
// Parses the live options and runs run_live(); returns the process exit code.
int live_main(int argc, char** argv);

}  // namespace hapfluid::sim
