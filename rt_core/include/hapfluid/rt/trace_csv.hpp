// The trace file format: CSV, one row per tick, written by haptic-trace, by haptic-rt's own
// drainer (--trace) and by flight-recorder dumps; read by hapfluid.latency_report.
//   tick, scheduled_ns, wake_ns, wake_latency_ns, compute_ns, io_ns, sim_age_ns, loop_flags,
//   overruns, sim_device_tick, sim_publish_ns, send_ns, then per device i: d<i>_flags, d<i>_faults,
//   d<i>_fx..fz (N), d<i>_tx..tz (N*m), d<i>_fresh, d<i>_miss_run, d<i>_state_seq,
//   d<i>_state_receive_ns, d<i>_cmd_seq
// (field meanings: shm::TraceRecord in layouts.hpp).
// Flags are the numeric rt::LoopFlag / safety::Flag / safety::Fault bits.
#pragma once

#include <cstdio>

#include "hapfluid/shm/layouts.hpp"

namespace hapfluid::rt {

void write_trace_header(std::FILE* out, unsigned device_count);
void write_trace_row(std::FILE* out, const shm::TraceRecord& record, unsigned device_count);

}  // namespace hapfluid::rt
