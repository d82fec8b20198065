// Rig file schema and validation. docs/config-reference.md documents every key.
#include "hapfluid/config/rig.hpp"

#include <algorithm>
#include <cstdio>
#include <set>

#include "load_toml.hpp"
#include "toml_reader.hpp"
#include "hapfluid/wire/codec.h"

namespace hapfluid::config {
namespace {

using detail::Reader;

Transport read_transport(Reader& r) {
  Transport t;
  t.kind = r.choice<TransportKind>("kind", TransportKind::loopback,
                                   {{"loopback", TransportKind::loopback},
                                    {"socketcan", TransportKind::socketcan},
                                    {"hid", TransportKind::hid},
                                    {"usb_bulk", TransportKind::usb_bulk}});
  if (auto address = r.required_string("address")) t.address = *address;
  r.check("address", !t.address.empty() || !r.has("address"), "must not be empty");
  t.can_node_id = static_cast<std::uint32_t>(r.integer("can_node_id", 1));
  r.check("can_node_id", t.can_node_id >= 1 && t.can_node_id <= 15, "must be 1..15 (4-bit node id)");
  t.can_fd = r.boolean("can_fd", false);
  t.framing = r.string("framing", t.kind == TransportKind::hid        ? "hid"
                                  : t.kind == TransportKind::usb_bulk ? "bulk"
                                  : t.can_fd                          ? "canfd"
                                                                      : "can");
  static const std::set<std::string> framings{"can", "canfd", "hid", "bulk"};
  r.check("framing", framings.count(t.framing) == 1, "must be one of \"can\", \"canfd\", \"hid\", \"bulk\"");
  if (t.kind == TransportKind::hid || t.kind == TransportKind::usb_bulk) {
    // "vid:pid" in hex, or a device path for hid.
    bool path = t.address.rfind("/dev/", 0) == 0;
    bool vidpid = t.address.size() == 9 && t.address[4] == ':';
    r.check("address", path || vidpid || t.address.empty(),
            t.kind == TransportKind::hid ? "must be \"vid:pid\" (hex, e.g. \"1209:4f48\") or a /dev/hidraw path"
                                         : "must be \"vid:pid\" (hex, e.g. \"1209:4f48\")");
  }
  r.finish();
  return t;
}

WorkspaceMapping read_mapping(Reader& r) {
  WorkspaceMapping m;
  m.offset_m = r.vec3("offset_m", m.offset_m);
  r.positive("scale", m.scale);
  m.rotation = r.quaternion("rotation", m.rotation);
  r.positive("force_scale", m.force_scale);
  r.finish();
  return m;
}

void read_limits(Reader& r, DeviceLimits& l) {
  r.positive("max_force_n", l.max_force_n);
  r.positive("max_torque_nm", l.max_torque_nm);
  // Per-axis limits default to the norm limit.
  l.max_force_axis_n = {l.max_force_n, l.max_force_n, l.max_force_n};
  l.max_torque_axis_nm = {l.max_torque_nm, l.max_torque_nm, l.max_torque_nm};
  l.max_force_axis_n = r.vec3("max_force_axis_n", l.max_force_axis_n);
  l.max_torque_axis_nm = r.vec3("max_torque_axis_nm", l.max_torque_axis_nm);
  for (auto [key, v] : {std::pair{"max_force_axis_n", l.max_force_axis_n}, {"max_torque_axis_nm", l.max_torque_axis_nm}})
    if (r.has(key)) r.check(key, v.x > 0 && v.y > 0 && v.z > 0, "every component must be > 0");
  // The wire carries each axis of the wrench up to its full scale: a limit beyond it promises a
  // force the host can never send (the encoder refuses it, and a disabled zero goes instead).
  char wire[96];
  std::snprintf(wire, sizeof wire, "must be <= %g N, the full scale of the wire (firmware_bridge/protocol.md 1.2)",
                HF_WIRE_MAX_FORCE_N);
  r.check("max_force_n", l.max_force_n <= HF_WIRE_MAX_FORCE_N, wire);
  if (r.has("max_force_axis_n"))
    r.check("max_force_axis_n", std::max({l.max_force_axis_n.x, l.max_force_axis_n.y, l.max_force_axis_n.z}) <=
                                    HF_WIRE_MAX_FORCE_N, std::string("every component ") + wire);
  std::snprintf(wire, sizeof wire, "must be <= %g N*m, the full scale of the wire (firmware_bridge/protocol.md 1.2)",
                HF_WIRE_MAX_TORQUE_NM);
  r.check("max_torque_nm", l.max_torque_nm <= HF_WIRE_MAX_TORQUE_NM, wire);
  if (r.has("max_torque_axis_nm"))
    r.check("max_torque_axis_nm", std::max({l.max_torque_axis_nm.x, l.max_torque_axis_nm.y, l.max_torque_axis_nm.z}) <=
                                      HF_WIRE_MAX_TORQUE_NM, std::string("every component ") + wire);
  r.positive("max_force_rate_n_per_s", l.max_force_rate_n_per_s);
  r.positive("max_torque_rate_nm_per_s", l.max_torque_rate_nm_per_s);
  r.positive("max_stiffness_n_per_m", l.max_stiffness_n_per_m);
  r.positive("max_angular_stiffness_nm_per_rad", l.max_angular_stiffness_nm_per_rad);
  r.positive("max_coupling_damping_n_s_per_m", l.max_coupling_damping_n_s_per_m);
  r.positive("max_coupling_angular_damping_nm_s_per_rad", l.max_coupling_angular_damping_nm_s_per_rad);
  l.device_damping_n_s_per_m = r.number("device_damping_n_s_per_m", l.device_damping_n_s_per_m);
  r.check("device_damping_n_s_per_m", l.device_damping_n_s_per_m >= 0, "must be >= 0");
}

void read_watchdogs(Reader& r, Watchdogs& w) {
  r.positive("sim_stale_ms", w.sim_stale_ms);
  r.positive("sim_ramp_down_ms", w.sim_ramp_down_ms);
  r.positive("link_timeout_ms", w.link_timeout_ms);
  r.positive("link_recover_ms", w.link_recover_ms);
  r.positive("engage_threshold_n", w.engage_threshold_n);
  w.engage_threshold_nm = r.number("engage_threshold_nm", 0.0);
  r.check("engage_threshold_nm", w.engage_threshold_nm >= 0, "must be >= 0 (0: derived from engage_threshold_n)");
  r.positive("engage_ramp_ms", w.engage_ramp_ms);
  w.engage_small_ms = r.number("engage_small_ms", w.engage_small_ms);
  r.check("engage_small_ms", w.engage_small_ms >= 0, "must be >= 0 (0: a small command engages at once)");
  w.engage_hold_ms = r.number("engage_hold_ms", w.engage_hold_ms);
  r.check("engage_hold_ms", w.engage_hold_ms >= 0, "must be >= 0 (0: only a small command engages)");
  r.positive("engage_steady_band_n", w.engage_steady_band_n);
  w.engage_steady_band_nm = r.number("engage_steady_band_nm", 0.0);
  r.check("engage_steady_band_nm", w.engage_steady_band_nm >= 0, "must be >= 0 (0: derived from engage_steady_band_n)");
  r.positive("engage_ramp_rate_n_per_s", w.engage_ramp_rate_n_per_s);
  w.engage_ramp_rate_nm_per_s = r.number("engage_ramp_rate_nm_per_s", 0.0);
  r.check("engage_ramp_rate_nm_per_s", w.engage_ramp_rate_nm_per_s >= 0,
          "must be >= 0 (0: derived from engage_ramp_rate_n_per_s)");
  r.positive("device_watchdog_ms", w.device_watchdog_ms);
  r.positive("lost_command_window_ms", w.lost_command_window_ms);
  r.positive("max_lost_commands", w.max_lost_commands);
  r.check("device_watchdog_ms", w.device_watchdog_ms <= HF_WIRE_MAX_WATCHDOG_MS,
          "must be <= 255 ms, the most a device reports in its INFO (firmware_bridge/protocol.md 2)");
}

RigDevice read_device(Reader& r) {
  RigDevice d;
  if (auto name = r.required_string("name")) d.name = *name;
  d.kind = r.choice<DeviceKind>("kind", DeviceKind::haptic_arm,
                                {{"haptic_arm", DeviceKind::haptic_arm}, {"spacemouse", DeviceKind::spacemouse}});
  if (auto t = r.table("transport")) {
    d.transport = read_transport(*t);
  } else {
    r.problem("transport", "missing (a [devices.transport] table with kind and address is required)");
  }
  if (auto m = r.table("mapping")) d.mapping = read_mapping(*m);
  read_limits(r, d.limits);
  read_watchdogs(r, d.watchdogs);
  // The engage ramp is the slow, deliberate rise; the per-tick rate limit must never be what
  // shapes it.
  r.check("engage_ramp_rate_n_per_s", d.watchdogs.engage_ramp_rate_n_per_s <= d.limits.max_force_rate_n_per_s,
          "must be <= max_force_rate_n_per_s (lower it, or raise the rate limit)");
  r.check("engage_ramp_rate_nm_per_s", d.watchdogs.engage_ramp_rate_nm_per_s <= d.limits.max_torque_rate_nm_per_s,
          "must be <= max_torque_rate_nm_per_s (lower it, or raise the rate limit)");
  if (auto p = r.table("passivity")) {
    d.passivity.enabled = p->boolean("enabled", d.passivity.enabled);
    p->positive("max_damping_n_s_per_m", d.passivity.max_damping_n_s_per_m);
    p->positive("max_damping_nm_s_per_rad", d.passivity.max_damping_nm_s_per_rad);
    p->positive("energy_cap_j", d.passivity.energy_cap_j);
    p->finish();
  }
  d.wrench_mode = r.choice<WrenchMode>("wrench_mode", WrenchMode::interpolate,
                                       {{"interpolate", WrenchMode::interpolate}, {"coupling", WrenchMode::coupling}});
  d.require_deadman = r.boolean("require_deadman", false);
  if (d.kind == DeviceKind::spacemouse)
    r.check("kind", d.transport.kind == TransportKind::hid || d.transport.kind == TransportKind::loopback,
            "a spacemouse is an input-only HID device: transport.kind must be \"hid\" or \"loopback\"");
  r.finish();
  return d;
}

RtSettings read_rt(Reader& r) {
  RtSettings rt;
  rt.period_ns = r.integer("period_ns", rt.period_ns);
  r.check("period_ns", rt.period_ns >= 100'000 && rt.period_ns <= 100'000'000, "must be 100000..100000000 (0.1-100 ms)");
  rt.wake_phase_ns = r.integer("wake_phase_ns", rt.period_ns / 4);
  r.check("wake_phase_ns", rt.wake_phase_ns >= 0 && rt.wake_phase_ns < rt.period_ns, "must be 0 <= wake_phase_ns < period_ns");
  rt.priority = static_cast<int>(r.integer("priority", rt.priority));
  r.check("priority", rt.priority >= 1 && rt.priority <= 99, "must be a SCHED_FIFO priority 1..99");
  rt.cpu = static_cast<int>(r.integer("cpu", rt.cpu));
  r.check("cpu", rt.cpu >= -1 && rt.cpu < 1024, "must be -1 (no pinning) or a CPU number");
  rt.policy = r.choice<RtPolicy>("policy", RtPolicy::ignore, {{"enforce", RtPolicy::enforce}, {"ignore", RtPolicy::ignore}});
  rt.trace_ring_records = static_cast<std::uint32_t>(r.integer("trace_ring_records", rt.trace_ring_records));
  r.check("trace_ring_records",
          rt.trace_ring_records >= 64 && (rt.trace_ring_records & (rt.trace_ring_records - 1)) == 0,
          "must be a power of two >= 64");
  rt.flight_recorder_ticks = static_cast<std::uint32_t>(r.integer("flight_recorder_ticks", rt.flight_recorder_ticks));
  r.check("flight_recorder_ticks", rt.flight_recorder_ticks >= 1 && rt.flight_recorder_ticks <= 100000, "must be 1..100000");
  if (auto shm = r.table("shm")) {
    rt.shm.prefix = shm->string("prefix", rt.shm.prefix);
    bool ok = !rt.shm.prefix.empty() && rt.shm.prefix.find('/') == std::string::npos && rt.shm.prefix.size() < 200;
    shm->check("prefix", ok, "must be a non-empty name without '/'");
    rt.shm.group = shm->string("group", rt.shm.group);
    shm->finish();
  }
  r.finish();
  return rt;
}

}  // namespace

const RigDevice* Rig::find_device(const std::string& wanted) const {
  for (const auto& d : devices)
    if (d.name == wanted) return &d;
  return nullptr;
}

Rig parse_rig(const std::string& text, const std::filesystem::path& file) {
  toml::table root = detail::parse_toml(text, file);
  detail::Diagnostics diag{file.string(), {}};
  Reader r(root, "", diag);
  Rig rig;
  rig.file = file;
  rig.name = r.string("name", file.stem().string());
  if (auto rt = r.table("rt")) rig.rt = read_rt(*rt);
  if (auto d = r.table("dashboard")) {
    rig.dashboard.address = d->string("address", rig.dashboard.address);
    const std::string& a = rig.dashboard.address;
    const auto colon = a.rfind(':');
    const std::string port = colon == std::string::npos ? "" : a.substr(colon + 1);
    const bool digits = !port.empty() && port.size() <= 5 && port.find_first_not_of("0123456789") == std::string::npos;
    if (colon == 0 || colon == std::string::npos || !digits || std::stoi(port) < 1 || std::stoi(port) > 65535)
      d->problem("address", "\"" + a + "\" is not HOST:PORT (e.g. \"127.0.0.1:8642\")");
    d->finish();
  }
  std::set<std::string> names;
  for (auto& device : r.tables("devices")) {
    rig.devices.push_back(read_device(device));
    const std::string& name = rig.devices.back().name;
    if (!name.empty() && !names.insert(name).second)
      device.problem("name", "duplicate device name \"" + name + "\"");
  }
  if (!r.has("devices")) r.problem("devices", "missing (at least one [[devices]] entry is required)");
  r.finish();
  diag.throw_if_any();
  return rig;
}

Rig load_rig(const std::filesystem::path& file) {
  return parse_rig(detail::read_text_file(file, "rig"), file);
}

const char* to_string(DeviceKind k) { return k == DeviceKind::haptic_arm ? "haptic_arm" : "spacemouse"; }
const char* to_string(TransportKind k) {
  switch (k) {
    case TransportKind::loopback: return "loopback";
    case TransportKind::socketcan: return "socketcan";
    case TransportKind::hid: return "hid";
    case TransportKind::usb_bulk: return "usb_bulk";
  }
  return "?";
}
const char* to_string(WrenchMode m) { return m == WrenchMode::interpolate ? "interpolate" : "coupling"; }
const char* to_string(RtPolicy p) { return p == RtPolicy::enforce ? "enforce" : "ignore"; }

}  // namespace hapfluid::config
