#!/usr/bin/env python3
"""Runs every libFuzzer target of the fuzzing build, one after the other, and writes one JSON.

The targets are the executables in BUILD/fuzz/ (tests/fuzz/, docs/fuzzing.md). Each runs in one
process for --runs executions from its corpus OUT/corpus/<target> (kept between campaigns) and
the seeds BUILD/tests/fuzz_seeds writes to OUT/seeds/<target>. A crash, a sanitizer report, a
leak, a timeout or an out-of-memory stops that target and leaves its input in
OUT/artifacts/<target>/; the script then exits non-zero. Results: OUT/fuzz.json, logs OUT/logs/.

    scripts/run_fuzz.py [--build build-fuzz] [--out out/fuzz] [--runs 1000000] [--only SUBSTRING]
"""
import argparse
import json
import os
import pathlib
import re
import shutil
import subprocess
import sys
import tempfile
import threading
import time

ROOT = pathlib.Path(__file__).resolve().parent.parent
# libFuzzer's status lines: "#262144	pulse  cov: 377 ft: 684 corp: 95/226Kb lim: 6402 exec/s: 13107 rss: 185Mb"
STATUS = re.compile(r"^#(\d+)\s+(\w+)\s+(?:cov: (\d+) )?(?:ft: (\d+) )?(?:corp: (\d+)/(\d+)(b|Kb|Mb|Gb) )?"
                    r"(?:.*?exec/s: (\d+))?(?:.*?rss: (\d+)Mb)?")
UNIT_BYTES = {"b": 1, "Kb": 1 << 10, "Mb": 1 << 20, "Gb": 1 << 30}
# Artifacts that are failures (libFuzzer also writes slow-unit-* only when asked to).
FAILURE_PREFIXES = ("crash-", "leak-", "timeout-", "oom-")


def discover(build: pathlib.Path):
    fuzz_dir = build / "fuzz"
    if not fuzz_dir.is_dir():
        return []
    return sorted(p for p in fuzz_dir.iterdir() if p.is_file() and os.access(p, os.X_OK))


def sanitizer_environment():
    env = dict(os.environ)
    symbolizer = shutil.which("llvm-symbolizer-14") or shutil.which("llvm-symbolizer")
    if symbolizer:
        env.setdefault("ASAN_SYMBOLIZER_PATH", symbolizer)
    env.setdefault("UBSAN_OPTIONS", "print_stacktrace=1")
    return env


class Progress:
    """Follows a target's libFuzzer output: keeps the newest status, prints one line now and then."""

    def __init__(self, name, runs, log, every_s=15.0):
        self.name, self.runs, self.log, self.every_s = name, runs, log, every_s
        self.status, self.seed, self.stats = {}, None, {}
        self._started = self._last_print = time.monotonic()

    def feed(self, line):
        self.log.write(line)
        if line.startswith("INFO: Seed: "):
            self.seed = int(line.split()[2])
        elif line.startswith("stat::"):
            key, _, value = line[len("stat::"):].partition(":")
            self.stats[key.strip()] = float(value)
        elif (m := STATUS.match(line)) and m.group(3):
            self.status = {
                "execs": int(m.group(1)),
                "event": m.group(2),
                "coverage_edges": int(m.group(3)),
                "features": int(m.group(4)) if m.group(4) else None,
                "corpus_units": int(m.group(5)) if m.group(5) else None,
                "corpus_bytes": int(m.group(6)) * UNIT_BYTES[m.group(7)] if m.group(5) else None,
                "exec_per_s": int(m.group(8)) if m.group(8) else None,
                "rss_mb": int(m.group(9)) if m.group(9) else None,
            }
            self.maybe_print()

    def maybe_print(self):
        """One line every every_s seconds; libFuzzer reports when it finds something and at powers of 2."""
        now = time.monotonic()
        if now - self._last_print < self.every_s:
            return
        self._last_print = now
        s = self.status
        if not s:
            print(f"    {self.name}: {now - self._started:6.0f} s, loading the corpus", flush=True)
            return
        print(f"    {self.name}: {now - self._started:6.0f} s, {s['execs']:>9}/{self.runs} execs"
              f" ({100 * s['execs'] / self.runs:5.1f} %, as of its last report), {s['exec_per_s'] or 0} exec/s,"
              f" cov {s['coverage_edges']}, corpus {s['corpus_units']}", flush=True)


def run_target(exe, args, out, seeds, env):
    name = exe.name
    corpus = out / "corpus" / name
    artifacts = out / "artifacts" / name
    for d in (corpus, artifacts, out / "logs"):
        d.mkdir(parents=True, exist_ok=True)
    before = {p.name for p in artifacts.iterdir()}
    corpus_at_start = sum(1 for _ in corpus.iterdir())
    command = [str(exe), f"-runs={args.runs}", "-print_final_stats=1", f"-timeout={args.timeout}",
               f"-rss_limit_mb={args.rss_limit_mb}", f"-artifact_prefix={artifacts}/", str(corpus)]
    if (seeds / name).is_dir():
        command.append(str(seeds / name))
    log_path = out / "logs" / f"{name}.log"
    started = time.monotonic()
    with open(log_path, "w") as log:
        log.write(" ".join(command) + "\n")
        process = subprocess.Popen(command, cwd=ROOT, env=env, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE,
                                   text=True, errors="replace")
        progress = Progress(name, args.runs, log)
        reader = threading.Thread(target=lambda: [progress.feed(line) for line in process.stderr])
        reader.start()
        while process.poll() is None:
            time.sleep(1)
            progress.maybe_print()
        returncode = process.wait()
        reader.join()
    wall_s = time.monotonic() - started
    # The harnesses remove their shm object, socket and scratch folder on a clean exit; a crash
    # leaves them behind.
    for leftover in (pathlib.Path(f"/dev/shm/hapfluid-fuzz-{process.pid}.segment"),
                     pathlib.Path(f"/tmp/hapfluid-fuzz-arm-{process.pid}.sock")):
        leftover.unlink(missing_ok=True)
    shutil.rmtree(pathlib.Path(tempfile.gettempdir()) / f"hapfluid-fuzz-scene-{process.pid}", ignore_errors=True)
    failures = sorted(str(artifacts / p.name) for p in artifacts.iterdir()
                      if p.name not in before and p.name.startswith(FAILURE_PREFIXES))
    status, stats = progress.status, progress.stats
    execs = int(stats.get("number_of_executed_units", status.get("execs", 0)))
    crashes = len(failures) + (1 if returncode != 0 and not failures else 0)
    return {
        "target": name,
        "execs": execs,
        "crashes": crashes,
        "exit_code": returncode,
        "wall_s": round(wall_s, 1),
        "exec_per_s": round(execs / wall_s) if wall_s > 0 else None,
        "corpus_units": status.get("corpus_units"),
        "corpus_bytes": status.get("corpus_bytes"),
        "corpus_files_at_start": corpus_at_start,
        "corpus_files": sum(1 for _ in corpus.iterdir()),
        "coverage_edges": status.get("coverage_edges"),
        "features": status.get("features"),
        "new_units_added": int(stats["new_units_added"]) if "new_units_added" in stats else None,
        "peak_rss_mb": int(stats["peak_rss_mb"]) if "peak_rss_mb" in stats else status.get("rss_mb"),
        "seed": progress.seed,
        "artifacts": failures,
        "reproduce": [f"{exe} {a}" for a in failures],
        "log": str(log_path),
    }


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--build", default="build-fuzz")
    parser.add_argument("--out", default="out/fuzz")
    parser.add_argument("--runs", type=int, default=1_000_000, help="executions per target (default 1000000)")
    parser.add_argument("--only", default="", help="run only targets whose name contains this")
    parser.add_argument("--timeout", type=int, default=10, help="seconds one input may take before it counts as a hang")
    parser.add_argument("--rss-limit-mb", type=int, default=2048, help="memory beyond which a target counts as failed")
    args = parser.parse_args()
    build, out = pathlib.Path(args.build).resolve(), pathlib.Path(args.out).resolve()
    out.mkdir(parents=True, exist_ok=True)

    targets = [t for t in discover(build) if args.only in t.name]
    if not targets:
        print(f"run_fuzz: no fuzz targets in {build}/fuzz (build them: make fuzz, or cmake --build {build} --target fuzzers)")
        return 2
    seeds = out / "seeds"
    subprocess.run([str(build / "tests" / "fuzz_seeds"), str(seeds)], check=True, cwd=ROOT)
    env = sanitizer_environment()
    results = []
    for index, exe in enumerate(targets, 1):
        print(f"[{index}/{len(targets)}] {exe.name}: {args.runs} runs ...", flush=True)
        r = run_target(exe, args, out, seeds, env)
        results.append(r)
        verdict = "ok" if r["crashes"] == 0 else f"FAILED ({r['crashes']} crash, exit {r['exit_code']})"
        print(f"[{index}/{len(targets)}] {exe.name}: {verdict}: {r['execs']} execs in {r['wall_s']} s "
              f"({r['exec_per_s']} exec/s), cov {r['coverage_edges']}, corpus {r['corpus_units']} units", flush=True)
        for line in r["reproduce"]:
            print(f"    reproduce: {line}")
        # Written after every target, so an interrupted campaign keeps what it measured.
        passed = all(x["crashes"] == 0 and x["execs"] >= args.runs for x in results)
        report = {
            "pass": passed and len(results) == len(targets),
            "runs_per_target": args.runs,
            "sanitizers": "address,undefined (-fno-sanitize-recover=undefined), libFuzzer",
            "processes": 1,
            "targets": results,
        }
        (out / "fuzz.json").write_text(json.dumps(report, indent=1) + "\n")

    print()
    print(f"{'target':<14} {'execs':>9} {'crashes':>7} {'wall_s':>8} {'exec/s':>7} {'corpus':>6} {'cov':>6}")
    for r in results:
        print(f"{r['target']:<14} {r['execs']:>9} {r['crashes']:>7} {r['wall_s']:>8} {r['exec_per_s'] or 0:>7} "
              f"{r['corpus_units'] or 0:>6} {r['coverage_edges'] or 0:>6}")
    short = [r["target"] for r in results if r["crashes"] == 0 and r["execs"] < args.runs]
    if short:
        print(f"run_fuzz: fewer than {args.runs} executions: {', '.join(short)}")
    failed = [r["target"] for r in results if r["crashes"]]
    print(f"run_fuzz: {'PASS' if report['pass'] else 'FAIL'}: {len(results) - len(failed)}/{len(results)} targets "
          f"without a crash; {out / 'fuzz.json'}")
    return 0 if report["pass"] else 1


if __name__ == "__main__":
    sys.exit(main())
