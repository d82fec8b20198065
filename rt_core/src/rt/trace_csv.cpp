#include "hapfluid/rt/trace_csv.hpp"

#include <cinttypes>

namespace hapfluid::rt {

void write_trace_header(std::FILE* out, unsigned devices) {
  std::fputs("tick,scheduled_ns,wake_ns,wake_latency_ns,compute_ns,io_ns,sim_age_ns,loop_flags,overruns,"
             "sim_device_tick,sim_publish_ns,send_ns", out);
  for (unsigned i = 0; i < devices; ++i)
    std::fprintf(out,
                 ",d%u_flags,d%u_faults,d%u_fx,d%u_fy,d%u_fz,d%u_tx,d%u_ty,d%u_tz,d%u_fresh,d%u_miss_run,d%u_state_seq,"
                 "d%u_state_receive_ns,d%u_cmd_seq",
                 i, i, i, i, i, i, i, i, i, i, i, i, i);
  std::fputc('\n', out);
}

void write_trace_row(std::FILE* out, const shm::TraceRecord& r, unsigned devices) {
  // Modulo 2^64 like the stamps themselves: a record from another process may hold any values,
  // and a signed difference of two stamps could overflow.
  const auto wake_latency_ns = static_cast<std::int64_t>(r.wake_ns - r.scheduled_ns);
  std::fprintf(out, "%" PRIu64 ",%" PRIu64 ",%" PRIu64 ",%" PRId64 ",%u,%u,%" PRId64 ",%u,%u,%" PRIu64 ",%" PRIu64 ",%" PRIu64,
               r.tick,
               r.scheduled_ns, r.wake_ns, wake_latency_ns, r.compute_ns,
               r.io_ns, r.sim_age_ns, r.loop_flags, r.overruns, r.sim_device_tick, r.sim_publish_ns, r.send_ns);
  for (unsigned i = 0; i < devices && i < unsigned(shm::kMaxDevices); ++i) {
    const auto& d = r.devices[i];
    std::fprintf(out, ",%u,%u,%.6g,%.6g,%.6g,%.6g,%.6g,%.6g,%u,%u,%u,%" PRIu64 ",%u", d.safety_flags, d.faults,
                 d.force_n[0], d.force_n[1], d.force_n[2], d.torque_nm[0], d.torque_nm[1], d.torque_nm[2], d.fresh,
                 d.link_miss_run, unsigned(d.state_sequence), d.state_receive_ns, unsigned(d.command_sequence));
  }
  std::fputc('\n', out);
}

}  // namespace hapfluid::rt
