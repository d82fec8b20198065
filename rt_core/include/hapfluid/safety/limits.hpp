// The memoryless stages of the safety layer: pure functions of their inputs, each reporting what
// it did as Flag bits. Every scaling is uniform over the vector, so the direction of the force
// (and of the torque) is preserved: a limited push is weaker, never sideways.
#pragma once

#include <cstdint>

#include "hapfluid/safety/flags.hpp"
#include "hapfluid/safety/safety_config.hpp"
#include "hapfluid/safety/wrench.hpp"

namespace hapfluid::safety {

// Any NaN/Inf component makes the whole wrench zero: a half-valid wrench has no trustworthy
// direction. Sets flag_nonfinite_input.
Wrench zero_if_nonfinite(const Wrench& command, std::uint32_t& flags);

// Norm limit, then per-axis limit, for force and torque separately. Both are uniform scalings,
// and the admissible set (ball intersected with box) is convex.
Wrench limit_magnitude(const Wrench& command, const SafetyConfig& config, std::uint32_t& flags);

// Limits the change from `previous` to at most max_*_rate * period per tick, scaling the change
// uniformly (so a convex combination of two admissible wrenches stays admissible).
Wrench limit_rate(const Wrench& target, const Wrench& previous, const SafetyConfig& config, std::uint32_t& flags);

// True when every limit of `config` holds for `w` (with a relative tolerance for rounding).
bool within_limits(const Wrench& w, const SafetyConfig& config, double tolerance = 1e-9);

}  // namespace hapfluid::safety
