"""The paper's qualitative results (§6.4-6.5, figs. 8-11), checked on a live run's histories.

Every check reads one launcher run folder (`python -m hapfluid run`) (or four, for the glass) and returns a
Verdict: whether the result holds, and the numbers it was judged on. Times are scene times, the
clock of the scene file's script (0 = the script's start): the hands play it on the wall clock,
so a sim slower than real time (it drops its backlog and says so) still sees every phase at the
same scene time, only with less simulated time in it.

  stirring  fig. 8   the force along the stroke opposes the hand's stroke velocity: mean F_x v_x < 0
                     (the device's log: what the hand felt, and its own position)
  probe     Alg. 1   as stirring, for a 3-DoF probe; and no torque ever reaches the device
  pouring   fig. 9   the vertical load moves from the bowl's hand to the pan's: level before the tilt
                     against level after the bowl is back
  glass     fig. 10  the fluid's share of the torque while the glass starts and stops grows with the
                     container's viscosity; in the steady spin the fluid co-rotates and the torque dies out
  bucket    fig. 11  both hands carry a comparable share of the weight while the bucket is level
  crepe     §6.5     as pouring (fig. 12: "the weight shifting between his hands as the batter goes from
                     the bowl to the pan"), and the batter stays in the pan while it is spread

The sim's coupling wrench (sim/couplings.csv: the force on the hand before the rig's limits) is
what the others are judged on: a rig limit (fake_single: 0.4 N·m) would otherwise decide fig. 10.
A live sim far slower than real time sees the hands' script (played on the wall clock) sped up by
1 / real-time factor (fig. 10 at 0.2: the glass spins at 5x the scripted speed for the fluid, and
the torque then says more about the machine than the viscosity); run_scenarios.py then judges the
scene's batch run instead (batch=True: the script at its own speed in simulated time). Fig. 10
compares four runs, and is always judged on their batch runs (run_scenarios.JUDGED_IN_BATCH).
"""
import csv
import json
import pathlib
import tomllib
from dataclasses import dataclass, field

import numpy as np

GRAVITY_M_S2 = 9.81
BATCH_DIR = "batch"  # run_scenarios.py's batch run of the same scene, beside a live run's sim/
MIN_WINDOW_S = 0.3  # a window with less than this much data cannot be judged
STEADY_AFTER_S = 1.0  # glass: the spin-up has diffused through the fluid (R^2 / nu = 0.8 s at 2 Pa·s)
STEADY_FRACTION = 0.05  # glass: the steady spin's torque against the start ramp's
RAMP_EDGES = (0.05, 0.95)  # glass: a ramp spans these fractions of the glass's own speed change


@dataclass
class Verdict:
    holds: bool
    text: str                 # one line: the claim, the numbers, why it fails
    numbers: dict = field(default_factory=dict)


class Run:
    """One launcher run folder: its scene, summary, sim couplings (scene time) and device logs.
    batch: judge the batch run beside it instead (BATCH_DIR: haptic-sim without the live stack,
    the scripted hands evaluated at simulated time, so scene time is simulated time)."""

    def __init__(self, folder: pathlib.Path, batch: bool = False):
        self.folder = pathlib.Path(folder)
        self.batch = batch
        with (self.folder / "scene.toml").open("rb") as f:
            self.scene = tomllib.load(f)
        self.offset_s, self.lead_in_s = 0.0, 0.0
        if batch:
            return
        self.summary = json.loads((self.folder / "summary.json").read_text())
        if "script_offset_s" not in self.summary:
            raise ValueError(f"{self.folder}/summary.json: no script_offset_s (the run has no device logs?)")
        self.offset_s = float(self.summary["script_offset_s"])
        self.lead_in_s = float(self.summary.get("lead_in_s", 1.5))

    def couplings_csv(self) -> pathlib.Path:
        return self.folder / (BATCH_DIR if self.batch else "sim") / "couplings.csv"

    def couplings(self, device: str) -> dict:
        """{column: array} of the sim's coupling rows of one device, "t" in scene time."""
        with self.couplings_csv().open(newline="") as f:
            rows = [r for r in csv.DictReader(f) if r["device"] == device]
        if not rows:
            raise ValueError(f"{self.couplings_csv()}: no rows for device '{device}'")
        clock = "t" if self.batch else "wall_s"
        data = {k: np.array([float(r[k]) for r in rows]) for k in (clock, "fx", "fy", "fz", "tx", "ty", "tz")}
        data["t"] = data[clock] - self.offset_s
        return data

    def body(self, name: str) -> dict:
        """{column: array} of the sim's rows of one body (bodies.csv: pose, velocity, and the
        fluid's force and torque on it), "t" in the sim's own time."""
        path = self.folder / (BATCH_DIR if self.batch else "sim") / "bodies.csv"
        with path.open(newline="") as f:
            rows = [r for r in csv.DictReader(f) if r["body"] == name]
        if len(rows) < 2:
            raise ValueError(f"{path}: {len(rows)} rows for body '{name}'")
        return {k: np.array([float(r[k]) for r in rows]) for k in rows[0] if k != "body"}

    def device_log(self, device: str) -> dict:
        """{column: array} of the fake device's log, "t" in scene time (its clock minus the lead-in)."""
        with (self.folder / f"device_{device}.csv").open(newline="") as f:
            rows = list(csv.DictReader(f))
        data = {k: np.array([float(r[k]) for r in rows]) for k in rows[0]}
        data["t"] = data["t_s"] - self.lead_in_s
        return data

    def device_holding(self, body: str) -> str:
        return next(c["device"] for c in self.scene.get("couplings", []) if c["body"] == body)

    def motions(self, device: str) -> list[dict]:
        return next(d for d in self.scene["devices"] if d["name"] == device).get("motion", [])

    def fluid_weight_n(self) -> float:
        """The weight of the fluid the sim made (its stats.json): a block poured into a vessel
        fills only part of its box."""
        stats_path = self.folder / (BATCH_DIR if self.batch else "sim") / "stats.json"
        stats = json.loads(stats_path.read_text())
        if "fluid_mass_kg" not in stats:
            raise ValueError(f"{stats_path}: no fluid_mass_kg (written by an older haptic-sim?)")
        return float(stats["fluid_mass_kg"]) * GRAVITY_M_S2


def window_mean(data: dict, key: str, start: float, stop: float, what: str) -> float:
    keep = (data["t"] >= start) & (data["t"] <= stop)
    covered = data["t"][keep].max() - data["t"][keep].min() if keep.sum() > 1 else 0.0
    if covered < min(MIN_WINDOW_S, stop - start) * 0.9:
        raise ValueError(f"{what}: only {covered:.2f} s of data in scene time {start:.2f}-{stop:.2f} s "
                         f"(history {data['t'][0]:.2f}-{data['t'][-1]:.2f} s): run longer")
    return float(np.mean(data[key][keep]))


def stirring(run: Run) -> Verdict:
    stroke = next(m for m in run.motions("hand") if m["kind"] == "oscillate")
    log = run.device_log("hand")
    start = stroke["start_s"] + stroke.get("ramp_s", 0.0)
    # While the sim published: after it stops the loop ramps the hand's force to zero.
    stop = min(stroke["stop_s"], log["t"][-1] - 0.2, run.couplings("hand")["t"][-1] - 0.2)
    if stop - start < 1.0:
        return Verdict(False, f"the stroke lasted {max(stop - start, 0):.2f} s of the run (from {start:g} s): too short "
                              "to judge, run longer")
    keep = (log["t"] >= start) & (log["t"] <= stop)
    vx = np.gradient(log["px"], log["t"])
    power = float(np.mean(log["applied_fx"][keep] * vx[keep]))
    corr = float(np.corrcoef(log["applied_fx"][keep], vx[keep])[0, 1])
    numbers = {"mean_force_times_velocity_w": round(power, 5), "correlation": round(corr, 3),
               "stroke_window_s": [round(start, 2), round(stop, 2)]}
    text = (f"mean F_x v_x over the stroke ({start:.1f}-{stop:.1f} s) = {power * 1e3:+.1f} mW, correlation {corr:+.2f}: "
            + ("the force opposes the stroke" if power < 0 else "the force does NOT oppose the stroke"))
    return Verdict(power < 0, text, numbers)


def probe(run: Run) -> Verdict:
    """Algorithm 1: as stirring (the hand feels the fluid against its stroke), and the same of
    the sim's own coupling force, against the hand's velocity at the sim's times: the 1 kHz
    loop's local spring alone, held over a sample's age, also pulls against any motion, so the
    device's log cannot tell the fluid's drag from the latency. And the 3-DoF device never gets
    a torque: every applied torque in its log is exactly zero."""
    against = stirring(run)
    log = run.device_log("hand")
    sim = run.couplings("hand")
    start, stop = against.numbers.get("stroke_window_s", (0.0, 0.0))
    keep = (sim["t"] >= start) & (sim["t"] <= stop)
    if keep.sum() < 10:
        return Verdict(False, f"{against.text}; only {int(keep.sum())} sim coupling rows in the stroke: run longer",
                       against.numbers)
    hand_v = np.interp(sim["t"][keep], log["t"], np.gradient(log["px"], log["t"]))
    sim_power = float(np.mean(sim["fx"][keep] * hand_v))
    torque = max(float(np.max(np.abs(log[k]))) for k in ("applied_tx", "applied_ty", "applied_tz"))
    torque_free = torque == 0.0
    text = (against.text + f"; the sim's coupling force times the hand's velocity {sim_power * 1e3:+.2f} mW: "
            + ("the fluid resists the probe" if sim_power < 0 else "the fluid does NOT resist the probe")
            + ("; no torque ever reached the device" if torque_free
               else f"; a torque of {torque:.3g} N·m reached the 3-DoF device"))
    numbers = {**against.numbers, "sim_force_times_velocity_w": round(sim_power, 6), "max_applied_torque_nm": torque}
    return Verdict(against.holds and sim_power < 0 and torque_free, text, numbers)


def load_shift(run: Run, giver_body: str, taker_body: str, tilt_device: str, after: tuple[float, float],
               share: float = 0.5) -> Verdict:
    """The vertical load (-F_z on the hand, N) of each hand level before the tilt and in `after`:
    the giver's hand must lose and the taker's gain more than `share` of the fluid's weight (most of
    the fluid moved; measured in batch: bowl_pouring's water -87% / +75%, some splashing past the pan,
    crepe -85% / +93%)."""
    tilt = run.motions(tilt_device)[0]
    before = (tilt["start_s"] - 0.6, tilt["start_s"])
    weight = run.fluid_weight_n()
    change, loads = {}, {}
    for body in (giver_body, taker_body):
        device = run.device_holding(body)
        data = run.couplings(device)
        loads[body] = [-window_mean(data, "fz", *before, f"{device} before"),
                       -window_mean(data, "fz", *after, f"{device} after")]
        change[body] = loads[body][1] - loads[body][0]
    holds = change[giver_body] < -share * weight and change[taker_body] > share * weight
    text = (f"vertical load {giver_body} hand {loads[giver_body][0]:.2f} -> {loads[giver_body][1]:.2f} N, {taker_body} hand "
            f"{loads[taker_body][0]:.2f} -> {loads[taker_body][1]:.2f} N (before {before[0]:g}-{before[1]:g} s, after "
            f"{after[0]:g}-{after[1]:g} s; fluid weight {weight:.2f} N, a shift must exceed {share * weight:.2f} N): "
            + ("the load moves to the " if holds else "the load does NOT move to the ") + f"{taker_body}'s hand")
    numbers = {"fluid_weight_n": round(weight, 3),
               **{f"{b}_load_n": [round(v, 3) for v in loads[b]] for b in loads}}
    return Verdict(holds, text, numbers)


def pouring(run: Run) -> Verdict:
    tilt = run.motions(run.device_holding("bowl"))[0]
    return load_shift(run, "bowl", "pan", run.device_holding("bowl"), (tilt["stop_s"] + 0.2, tilt["stop_s"] + 0.8))


def crepe(run: Run) -> Verdict:
    bowl_hand, pan_hand = run.device_holding("bowl"), run.device_holding("pan")
    pour = run.motions(bowl_hand)[0]
    spreads = run.motions(pan_hand)
    poured = load_shift(run, "bowl", "pan", bowl_hand, (pour["stop_s"], spreads[0]["start_s"]))
    if not poured.holds:
        return poured
    # Spread: the pan is tilted one way and the other; the batter must stay in it: once the pan is
    # level again its hand still carries at least 80% of the load the pour added.
    pan = run.couplings(pan_hand)
    end = spreads[-1]["stop_s"]
    after_spread = -window_mean(pan, "fz", end, end + 0.8, f"{pan_hand} after spreading")
    empty, after_pour = poured.numbers["pan_load_n"]
    kept = after_spread - empty >= 0.8 * (after_pour - empty)
    numbers = {**poured.numbers, "pan_load_after_spreading_n": round(after_spread, 3)}
    text = (poured.text + f"; after spreading ({end:g}-{end + 0.8:g} s) the pan hand carries {after_spread - empty:+.2f} N "
            f"of the pour's {after_pour - empty:+.2f} N: "
            + ("the batter stays in the pan" if kept else "the batter did NOT stay in the pan"))
    return Verdict(kept, text, numbers)


def spin_script(run: Run) -> tuple[dict, np.ndarray]:
    """The hand's spin motion and its unit axis."""
    spin = next(m for m in run.motions("hand") if m["kind"] == "spin")
    return spin, np.array(spin["axis"], dtype=float) / np.linalg.norm(spin["axis"])


def about(axis: np.ndarray, data: dict, prefix: str) -> np.ndarray:
    """The component along `axis` of the columns prefix + x, y, z."""
    return sum(axis[k] * data[prefix + c] for k, c in enumerate("xyz"))


def spin_phase_torques_nm(run: Run, felt: bool = False) -> dict:
    """Mean torque about the spin axis on the hand (its magnitude) while the glass speeds up (the
    start ramp), while it slows down (the stop ramp), and in the steady spin once the spin-up
    has diffused through the fluid (STEADY_AFTER_S after the start ramp). felt: what the device
    applied (its log, the 1 kHz loop's rendering), else the sim's coupling torque."""
    spin, axis = spin_script(run)
    data = run.device_log("hand") if felt else run.couplings("hand")
    data["spin_axis_torque"] = about(axis, data, "applied_t" if felt else "t")
    ramp = spin.get("ramp_s", 0.0)
    start, stop = spin["start_s"], spin["stop_s"]
    name = run.folder.name
    return {
        "start": abs(window_mean(data, "spin_axis_torque", start, start + ramp, f"{name} start ramp")),
        "stop": abs(window_mean(data, "spin_axis_torque", stop - ramp, stop, f"{name} stop ramp")),
        "steady": abs(window_mean(data, "spin_axis_torque", start + ramp + STEADY_AFTER_S, stop - ramp,
                                  f"{name} steady spin")),
    }


def fluid_inertia_in_ramps_kg_m2(run: Run) -> dict:
    """The moment of inertia the fluid adds to its glass while the glass starts and while it stops:
    the fluid's angular impulse on the glass about the spin axis over the glass's own ramp (from
    RAMP_EDGES[0] to RAMP_EDGES[1] of its speed change, linear between rows), divided by the
    glass's speed change over it, positive when the fluid resists the change. A fluid left at
    rest adds nothing; one dragged along whole adds its own inertia. The ramp is found in the
    glass's own motion, in the sim's time, so how the sim saw the hand's script (its latency,
    its steps) does not move the window; and the glass's own inertia, 80 % of the torque the
    hand feels in a ramp, is left out."""
    spin, axis = spin_script(run)
    body = run.body(next(c["body"] for c in run.scene["couplings"] if c["device"] == "hand"))
    t, w, torque = body["t"], about(axis, body, "w"), about(axis, body, "t")
    impulse = np.concatenate([[0.0], np.cumsum(0.5 * (torque[1:] + torque[:-1]) * np.diff(t))])
    speed = float(spin["angular_speed_rad_s"])

    def crossing(level: float, rising: bool, after: float) -> float:
        above = (w >= level) if rising else (w <= level)
        hits = np.nonzero(above[1:] & ~above[:-1] & (t[1:] > after))[0]
        if len(hits) == 0:
            raise ValueError(f"{run.folder.name}: the glass's spin about the axis never "
                             f"{'rises' if rising else 'falls'} through {level:.3g} rad/s after {after:.2f} s "
                             f"(history {t[0]:.2f}-{t[-1]:.2f} s): run longer")
        k = hits[0]
        return float(t[k] + (level - w[k]) / (w[k + 1] - w[k]) * (t[k + 1] - t[k]))

    def share(t0: float, t1: float) -> float:
        # Positive when the fluid resists the glass's change of speed, as a fluid must.
        return -(np.interp(t1, t, impulse) - np.interp(t0, t, impulse)) / (np.interp(t1, t, w) - np.interp(t0, t, w))

    lo, hi = (f * speed for f in RAMP_EDGES)
    up0 = crossing(lo, True, t[0])
    up1 = crossing(hi, True, up0)
    down0 = crossing(hi, False, up1)
    down1 = crossing(lo, False, down0)
    return {"start": share(up0, up1), "stop": share(down0, down1),
            "start_ramp_s": up1 - up0, "stop_ramp_s": down1 - down0}


def glass(runs: list[Run]) -> Verdict:
    """Fig. 10: the more viscous the container, the harder it drags the fluid along, so the torque
    the fluid takes while the glass starts and stops grows with the container's viscosity
    (strictly, 2 < 10 < 20 < 40 Pa·s; measured in the batch runs: the fluid adds 0.85 < 0.96 <
    1.00 < 1.04 e-4 kg·m² at the start, +3 to +13 % per step, so no margin is asked). Judged on the
    fluid's share (fluid_inertia_in_ramps_kg_m2): the hand also pays for the glass's own inertia,
    the same in all four and four times the fluid's share, so a few ms more or less of ramp inside
    a fixed window would decide the order of the hand's torques. In the steady spin the fluid
    turns with its glass as a rigid body: no shear, no torque. The hand's mean torque there stays
    below STEADY_FRACTION of its start ramp's; a fluid driven faster than its container (a
    boundary term that is not zero for a rigid rotation) would keep the hand paying there. The
    same holds for what the device applied in the live runs (their device logs, where a run has
    them): a 1 kHz loop rendering the spring against a sample's stale anchor makes the hand pay
    K w times the sample's age in the steady spin, though the sim asks for nothing."""
    viscosity = [float(r.scene["bodies"][0]["viscosity_pa_s"]) for r in runs]
    order = np.argsort(viscosity)
    viscosity = [viscosity[i] for i in order]
    phases = [spin_phase_torques_nm(runs[i]) for i in order]
    fluid = [fluid_inertia_in_ramps_kg_m2(runs[i]) for i in order]
    start = [f["start"] for f in fluid]
    stop = [f["stop"] for f in fluid]
    steady = [p["steady"] for p in phases]
    grows = all(b > a for a, b in zip(start, start[1:])) and all(b > a for a, b in zip(stop, stop[1:]))
    corotates = all(p["steady"] < STEADY_FRACTION * p["start"] for p in phases)
    live = [Run(runs[i].folder) for i in order]  # the device logs are the live runs'
    felt = [spin_phase_torques_nm(r, felt=True) for r in live if (r.folder / "device_hand.csv").exists()]
    felt_corotates = all(p["steady"] < STEADY_FRACTION * p["start"] for p in felt)
    holds = grows and corotates and felt_corotates
    pairs = ", ".join(f"{v:g} Pa·s {a * 1e4:.3f}/{b * 1e4:.3f}" for v, a, b in zip(viscosity, start, stop))
    hand = ", ".join(f"{p['start'] * 1e3:.2f}/{p['steady'] * 1e3:.3f}" for p in phases)
    text = (f"the fluid's added inertia in the start/stop ramps, 1e-4 kg·m²: {pairs}: "
            + ("grows" if grows else "does NOT grow") + " with the container's viscosity at start and stop; "
            + f"the hand's torque start/steady, mN·m: {hand}: "
            + (f"the steady spin costs < {STEADY_FRACTION:.0%} of the start" if corotates
               else f"the steady spin keeps >= {STEADY_FRACTION:.0%} of the start's torque: the fluid does NOT co-rotate")
            + ("" if not felt else "; the device applied start/steady, mN·m: "
               + ", ".join(f"{p['start'] * 1e3:.2f}/{p['steady'] * 1e3:.3f}" for p in felt) + ": "
               + ("the hand feels no steady drag" if felt_corotates
                  else f"the hand feels >= {STEADY_FRACTION:.0%} of the start's torque in the steady spin, a drag "
                       "the sim does NOT ask for")))
    numbers = {"viscosity_pa_s": viscosity, "fluid_start_inertia_kg_m2": [round(float(v), 9) for v in start],
               "fluid_stop_inertia_kg_m2": [round(float(v), 9) for v in stop],
               "ramp_s": [[round(float(f["start_ramp_s"]), 4), round(float(f["stop_ramp_s"]), 4)] for f in fluid],
               "start_torque_nm": [round(p["start"], 6) for p in phases],
               "stop_torque_nm": [round(p["stop"], 6) for p in phases],
               "steady_torque_nm": [round(t, 6) for t in steady],
               "felt_start_torque_nm": [round(p["start"], 6) for p in felt],
               "felt_steady_torque_nm": [round(p["steady"], 6) for p in felt]}
    return Verdict(holds, text, numbers)


def bucket(run: Run) -> Verdict:
    first_tilt = min(m["start_s"] for d in run.scene["devices"] for m in d.get("motion", []))
    level = (max(first_tilt - 0.6, 0.3 - run.offset_s), first_tilt)
    down = {d: -window_mean(run.couplings(d), "fz", *level, f"{d} level") for d in ("left", "right")}
    total = sum(down.values())
    shares = {d: f / total if total > 0 else 0.0 for d, f in down.items()}
    holds = total > 1.0 and all(0.3 <= s <= 0.7 for s in shares.values())
    text = (f"level ({level[0]:.1f}-{level[1]:g} s): left {down['left']:.2f} N, right {down['right']:.2f} N of "
            f"{total:.2f} N (shares {shares['left']:.0%} / {shares['right']:.0%}, each must be 30-70%): "
            + ("both hands carry the bucket" if holds else "the hands do NOT share the bucket's weight"))
    return Verdict(holds, text, {"load_n": {d: round(f, 3) for d, f in down.items()}, "total_n": round(total, 3)})


CHECKS = {"stirring": stirring, "probe": probe, "pouring": pouring, "glass": glass, "bucket": bucket, "crepe": crepe}


def check(scenario: str, folders: list[pathlib.Path], batch: bool = False) -> Verdict:
    """The scenario's verdict on its run folders (their batch runs if `batch`); a run that cannot
    be judged fails, saying why."""
    try:
        runs = [Run(f, batch) for f in folders]
        verdict = CHECKS[scenario](runs) if scenario == "glass" else CHECKS[scenario](runs[0])
    except (OSError, ValueError, KeyError, StopIteration, IndexError) as e:
        verdict = Verdict(False, f"cannot judge: {type(e).__name__}: {e}")
    verdict.numbers["judged_on"] = "batch" if batch else "live"
    return verdict
