"""End-to-end motion-to-force latency of the live stack: from the fake device sampling the hand's
pose to the device taking the command whose wrench the simulator computed FROM that pose.

Runs the stirring scene on the live stack (the launcher: fake hand stroking, haptic-rt,
haptic-sim --live, haptic-trace), or reads a finished run, and follows every sim sample the loop
rendered back to its pose, on one clock (CLOCK_MONOTONIC, shared by every process on the machine):

    a  pose sampled    the fake device's tick that sampled and sent STATE s      (device log: tick_ns, state_seq)
    b  pose read       the loop received s; s is the pose of tick T's device_states (trace: d0_state_seq,
                       d0_state_receive_ns of tick T)
    c  sim published   the sim stepped with tick T's pose and published        (trace: sim_device_tick = T,
                       the sample                                                sim_publish_ns; sim/couplings.csv)
    e  wrench sent     the first loop tick R rendering that sample sent COMMAND c (trace: send_ns, d0_cmd_seq)
    f  wrench taken    the fake device took c (or a later command) off the link  (device log: rx_ns, cmd_seq)

Pieces: device -> loop (b - a), loop -> sim (c - b: the pose waiting for the sim's next step, the
step), sim -> loop (e - c: the sample waiting for the next loop tick, rendering), loop -> device
(f - e); total f - a. Each point is stamped after the event before it could have caused it (the
device stamps a command after draining its link, the loop its send before writing), so no piece is
negative unless the matching is wrong. Sequence numbers match on their low 8 bits (classic CAN),
unambiguous within 128 ms at 1 kHz. Only samples rendered on an engaged device (no fault, not
waiting to engage) count: there the wrench the hand feels reacts. In coupling mode the spring part
of the local model (F0 - K (x - x0)) reacts within the tick; this is the latency of the fluid's
reaction F0. `loop_pipeline_ms` is this script's earlier number (loop tick T's wake -> tick R's
wake + I/O), kept for comparison.

A cruder cross-check needs no clocks: the force the fake device applied lags its hand's stroke
velocity; the lag maximising their (anti-)correlation is printed as well. It is mostly the
physics (the spoon follows the hand through its coupling spring, the fluid's drag builds up),
~200-250 ms in the stirring scene, not transport.

    hapfluid-motion-to-force [--build build] [--out out/latency] [--duration 8]
                               [--run RUN_DIR] [--trace CSV] [--device-log CSV] [--couplings CSV]

Writes <out>/motion_to_force.png (histogram and per-piece breakdown) and <out>/motion_to_force.json.
"""
import argparse
import csv
import json
import pathlib
import subprocess
import sys

import numpy as np

from .c_constants import Flag
from .paths import ROOT
PIECES = ("device_to_loop", "loop_to_sim", "sim_to_loop", "loop_to_device")
SEQUENCE_MODULUS = 256      # classic CAN carries the low 8 bits of every sequence number
MATCH_WINDOW_NS = 128e6     # half the modulus at 1 kHz: a match within it is unambiguous
WAITING_TO_ENGAGE, HARD_ZERO = Flag.waiting_to_engage, Flag.hard_zero


def load_columns(path: pathlib.Path, names, integer=False) -> dict:
    """Named columns of a CSV as arrays: int64 (exact CLOCK_MONOTONIC ns, sequences) or float."""
    with path.open(newline="") as f:
        rows = list(csv.DictReader(f))
    missing = [n for n in names if rows and n not in rows[0]]
    if missing:
        sys.exit(f"motion_to_force_latency: {path} has no column {', '.join(missing)}: written by an older build? "
                 f"(rebuild and run again)")
    if integer:
        return {n: np.array([int(r[n]) for r in rows], dtype=np.int64) for n in names}
    return {n: np.array([float(r[n]) for r in rows]) for n in names}


def rendered_samples(trace: dict, d: int):
    """Indices (into the tick-sorted trace) of the first tick rendering each sim sample on an
    engaged device, with no trace record lost just before it."""
    tick, pub, dtick = trace["tick"], trace["sim_publish_ns"], trace["sim_device_tick"]
    first = np.zeros(len(tick), dtype=bool)
    first[1:] = (pub[1:] != pub[:-1]) & (tick[1:] == tick[:-1] + 1)
    engaged = (trace[f"d{d}_faults"] == 0) & ((trace[f"d{d}_flags"] & (WAITING_TO_ENGAGE | HARD_ZERO)) == 0)
    return np.nonzero(first & engaged & (dtick > 0) & (pub > 0))[0]


def match_state(device: dict, seq: int, read_ns: int):
    """Device-log time of the STATE whose low 8 bits are `seq`, the last one sent before read_ns."""
    times = device["states_by_residue"].get(seq % SEQUENCE_MODULUS)
    if times is None:
        return None
    i = int(np.searchsorted(times, read_ns, side="right")) - 1
    if i < 0 or read_ns - times[i] > MATCH_WINDOW_NS:
        return None
    return int(times[i])


def match_command(device: dict, seq: int, sent_ns: int):
    """Device-log time at which the device had taken COMMAND `seq` (it, or a later one, which
    arrived after it): the first draining tick at or after sent_ns whose newest command is not
    older than seq."""
    rx, cmd = device["rx_ns"], device["cmd_seq"]
    i = int(np.searchsorted(rx, sent_ns, side="left"))
    while i < len(rx) and rx[i] - sent_ns <= MATCH_WINDOW_NS:
        if (int(cmd[i]) - seq) % SEQUENCE_MODULUS < SEQUENCE_MODULUS // 2:
            return int(rx[i])
        i += 1
    return None


def load_device_log(path: pathlib.Path) -> dict:
    log = load_columns(path, ("tick_ns", "rx_ns", "state_seq", "cmd_received", "cmd_seq"), integer=True)
    tick_ns, rx_ns, state_seq = log["tick_ns"], log["rx_ns"], log["state_seq"]
    sent = state_seq >= 0
    by_residue = {}
    for r in range(SEQUENCE_MODULUS):
        times = tick_ns[sent & (state_seq % SEQUENCE_MODULUS == r)]
        if len(times):
            by_residue[r] = np.sort(times)
    took = log["cmd_received"] == 1
    order = np.argsort(rx_ns[took], kind="stable")
    return {"states_by_residue": by_residue, "rx_ns": rx_ns[took][order], "cmd_seq": log["cmd_seq"][took][order]}


def load_trace(path: pathlib.Path, d: int) -> dict:
    names = ("tick", "wake_ns", "io_ns", "sim_device_tick", "sim_publish_ns", "send_ns", f"d{d}_flags",
             f"d{d}_faults", f"d{d}_state_seq", f"d{d}_state_receive_ns", f"d{d}_cmd_seq")
    trace = load_columns(path, names, integer=True)
    order = np.argsort(trace["tick"], kind="stable")
    return {k: v[order] for k, v in trace.items()}


def sim_samples(path: pathlib.Path):
    """(device_tick, publish_ns) of every sample the sim logged, or None without its log."""
    if not path or not path.exists():
        return None
    log = load_columns(path, ("device_tick", "publish_ns"), integer=True)
    return set(zip(log["device_tick"].tolist(), log["publish_ns"].tolist()))


def chains(trace: dict, device: dict, d: int = 0, sim_log=None) -> dict:
    """Per rendered sample: the points a, b, c, e, f (ns) and the old pipeline number (ms)."""
    points = {k: [] for k in ("a", "b", "c", "e", "f", "pipeline_ms", "confirmed")}
    ticks = trace["tick"]
    candidates = rendered_samples(trace, d)
    for r in candidates:
        t = trace["sim_device_tick"][r]
        i = int(np.searchsorted(ticks, t))
        if i >= len(ticks) or ticks[i] != t:
            continue  # the trace lost tick T
        b = int(trace[f"d{d}_state_receive_ns"][i])
        a = match_state(device, int(trace[f"d{d}_state_seq"][i]), b) if b > 0 else None
        c, e = int(trace["sim_publish_ns"][r]), int(trace["send_ns"][r])
        f = match_command(device, int(trace[f"d{d}_cmd_seq"][r]), e)
        if a is None or f is None:
            continue
        for k, v in (("a", a), ("b", b), ("c", c), ("e", e), ("f", f)):
            points[k].append(v)
        points["pipeline_ms"].append((trace["wake_ns"][r] + trace["io_ns"][r] - trace["wake_ns"][i]) * 1e-6)
        points["confirmed"].append(sim_log is None or (int(t), c) in sim_log)
    out = {k: np.array(v, dtype=np.int64 if k in "abcef" else float) for k, v in points.items()}
    out["confirmed"] = np.array(points["confirmed"], dtype=bool)
    out["candidates"] = len(candidates)
    return out


def pieces_ms(ch: dict) -> dict:
    a, b, c, e, f = (ch[k] for k in "abcef")
    return {"device_to_loop": (b - a) * 1e-6, "loop_to_sim": (c - b) * 1e-6, "sim_to_loop": (e - c) * 1e-6,
            "loop_to_device": (f - e) * 1e-6, "total": (f - a) * 1e-6, "loop_pipeline": ch["pipeline_ms"]}


def stats(values) -> dict:
    return {"p50": round(float(np.percentile(values, 50)), 3), "p99": round(float(np.percentile(values, 99)), 3),
            "max": round(float(np.max(values)), 3), "min": round(float(np.min(values)), 3)}


def correlation_lag_ms(device_log: pathlib.Path):
    """Lag (ms) at which the applied force best anti-correlates with the hand's stroke velocity;
    (None, None) without a stroke to correlate."""
    log = load_columns(device_log, ("t_s", "px", "applied_fx"))
    t, px, fx = log["t_s"], log["px"], log["applied_fx"]
    m = (t > 1.5) & (t < t[-1] - 1.0)
    if m.sum() < 500:
        return None, None
    vx = np.gradient(px, t)
    vx, fx = vx[m] - vx[m].mean(), fx[m] - fx[m].mean()
    if vx.std() < 1e-6 or fx.std() < 1e-6:
        return None, None
    lags = np.arange(0, 400)  # the stroke is 2 s long: a quarter period would correlate with position
    corr = [np.corrcoef(vx[: len(vx) - k], fx[k:])[0, 1] for k in lags]
    k = int(np.argmin(corr))
    return float(lags[k]), round(float(corr[k]), 3)


def analyse(trace_csv: pathlib.Path, device_csv: pathlib.Path, couplings_csv: pathlib.Path | None, d: int = 0):
    """The JSON result and the per-chain pieces (ms)."""
    ch = chains(load_trace(trace_csv, d), load_device_log(device_csv), d, sim_samples(couplings_csv))
    if len(ch["a"]) == 0:
        sys.exit(f"motion_to_force_latency: no rendered sim sample in {trace_csv} could be followed to the device "
                 f"log {device_csv} ({ch['candidates']} rendered on an engaged device; was haptic-rt coupled?)")
    p = pieces_ms(ch)
    lag, corr = correlation_lag_ms(device_csv)
    result = {
        "clock": "CLOCK_MONOTONIC",
        "samples": int(len(ch["a"])),
        "rendered_samples": int(ch["candidates"]),
        "confirmed_by_sim_log": int(ch["confirmed"].sum()),
        "total_ms": stats(p["total"]),
        "pieces_ms": {k: stats(p[k]) for k in PIECES},
        "loop_pipeline_ms": stats(p["loop_pipeline"]),
        "negative_pieces": int(sum((p[k] < 0).sum() for k in PIECES)),
        "sum_error_ms": float(np.max(np.abs(sum(p[k] for k in PIECES) - p["total"]))),
        "stroke_force_lag_ms": lag,
        "stroke_force_correlation": corr,
        "trace": str(trace_csv), "device_log": str(device_csv), "couplings": str(couplings_csv) if couplings_csv else None,
    }
    return result, p


def plot(result: dict, p: dict, path: pathlib.Path):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    fig, (a, b) = plt.subplots(1, 2, figsize=(12, 4.2), gridspec_kw={"width_ratios": [1.1, 1]})
    total = p["total"]
    a.hist(total, bins=60, color="tab:blue")
    for q, style in (("p50", "--"), ("p99", ":")):
        a.axvline(result["total_ms"][q], color="k", ls=style, label=f"{q} {result['total_ms'][q]} ms")
    a.set_xlabel("motion-to-force latency (ms)")
    a.set_ylabel("sim samples")
    a.set_title("pose sampled by the device -> command taken by the device")
    a.legend()
    labels = ["device -> loop", "loop -> sim\n(step)", "sim -> loop", "loop -> device", "loop pipeline\n(old number)"]
    horizontal = {"orientation": "horizontal"} if tuple(map(int, matplotlib.__version__.split(".")[:2])) >= (3, 10) \
        else {"vert": False}
    b.boxplot([p[k] for k in PIECES] + [p["loop_pipeline"]], whis=(1, 99), showfliers=False, **horizontal)
    left = 0.0
    for k, colour in zip(PIECES, ("tab:green", "tab:orange", "tab:purple", "tab:red")):
        w = result["pieces_ms"][k]["p50"]
        b.barh(len(labels) + 1, w, left=left, color=colour, height=0.6)
        left += w
    b.set_yticks(range(1, len(labels) + 2), labels + ["medians,\nstacked"])
    b.invert_yaxis()
    b.set_xlabel("ms (boxes p25-p75, whiskers p1-p99)")
    b.set_title("per piece")
    b.grid(alpha=0.3, axis="x")
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


def run_stack(args, run: pathlib.Path):
    cmd = [sys.executable, "-m", "hapfluid", "run", "--scene", "spoon_stirring", "--build",
           args.build, "--out", str(run), "--no-render", "--duration", str(args.duration)]
    print("motion_to_force_latency: " + " ".join(cmd), file=sys.stderr, flush=True)
    if subprocess.run(cmd, stdout=subprocess.DEVNULL).returncode != 0:
        sys.exit(f"motion_to_force_latency: the run failed; see {run}/logs")


def device_log_of(run: pathlib.Path) -> pathlib.Path:
    logs = sorted(run.glob("device_*.csv"))
    logs = [p for p in logs if p.name != "device_wrenches.csv"]
    if len(logs) != 1:
        sys.exit(f"motion_to_force_latency: {run}: expected one device_<name>.csv, found "
                 f"{[p.name for p in logs]}: name it with --device-log")
    return logs[0]


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--build", default="build")
    ap.add_argument("--out", default=str(ROOT / "out" / "latency"))
    ap.add_argument("--duration", type=float, default=8.0)
    ap.add_argument("--run", default=None, help="analyse an existing launcher run folder instead of running")
    ap.add_argument("--trace", default=None, help="trace CSV (default: <run>/trace.csv)")
    ap.add_argument("--device-log", default=None, help="the fake device's --log CSV (default: <run>/device_<name>.csv)")
    ap.add_argument("--couplings", default=None, help="the sim's couplings.csv (default: <run>/sim/couplings.csv)")
    ap.add_argument("--device-index", type=int, default=0, help="the trace's device (d<N>_ columns), default 0")
    args = ap.parse_args()
    out = pathlib.Path(args.out).resolve()
    out.mkdir(parents=True, exist_ok=True)
    run = pathlib.Path(args.run).resolve() if args.run else out / "run"
    if not (args.run or args.trace):
        run_stack(args, run)
    trace = pathlib.Path(args.trace) if args.trace else run / "trace.csv"
    device = pathlib.Path(args.device_log) if args.device_log else device_log_of(run)
    couplings = pathlib.Path(args.couplings) if args.couplings else run / "sim" / "couplings.csv"
    result, p = analyse(trace, device, couplings if couplings.exists() else None, args.device_index)
    (out / "motion_to_force.json").write_text(json.dumps(result, indent=2) + "\n")

    t, pc = result["total_ms"], result["pieces_ms"]
    print(f"motion-to-force latency (device samples the pose -> device takes the wrench computed from it), "
          f"{result['samples']} sim samples: p50 {t['p50']} ms, p99 {t['p99']} ms, max {t['max']} ms")
    for k in PIECES:
        print(f"  {k:15s} p50 {pc[k]['p50']:7.3f}  p99 {pc[k]['p99']:7.3f}  max {pc[k]['max']:7.3f} ms")
    lp = result["loop_pipeline_ms"]
    print(f"  (loop pipeline, the earlier number: p50 {lp['p50']} ms, p99 {lp['p99']} ms, max {lp['max']} ms)")
    if result["stroke_force_lag_ms"] is not None:
        print(f"cross-check: applied force lags the stroke velocity by {result['stroke_force_lag_ms']:.0f} ms "
              f"(correlation {result['stroke_force_correlation']:.2f}; the coupled spoon's and the fluid's response)")
    if result["negative_pieces"]:
        print(f"motion_to_force_latency: {result['negative_pieces']} negative pieces: the logs do not agree "
              f"(clocks or sequence matching)", file=sys.stderr)
    plot(result, p, out / "motion_to_force.png")
    print(f"motion_to_force_latency: {out / 'motion_to_force.png'}, {out / 'motion_to_force.json'}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
