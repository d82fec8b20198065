#!/usr/bin/env python3
"""Runs every benchmark and prints one table.

Benchmarks are executables in BUILD/bench/ (run as `NAME --out OUT/NAME.json`) and Python scripts
scripts/bench_*.py (run as `bench_X.py --build BUILD --out OUT/X.json`). Each writes a JSON list of
{"bench": NAME, "params": {...}, "metrics": {...}} records, units in the metric names.

    scripts/run_benchmarks.py [--build build] [--out out/bench] [--only SUBSTRING]
"""
import argparse
import json
import os
import pathlib
import subprocess
import sys
import time

ROOT = pathlib.Path(__file__).resolve().parent.parent


def discover(build: pathlib.Path):
    bench_dir = build / "bench"
    if bench_dir.is_dir():
        for exe in sorted(bench_dir.iterdir()):
            if exe.is_file() and os.access(exe, os.X_OK):
                yield exe.name, [str(exe)]
    for script in sorted((ROOT / "scripts").glob("bench_*.py")):
        yield script.stem, [sys.executable, str(script), "--build", str(build)]


def validate(records, source):
    if not isinstance(records, list):
        raise ValueError(f"{source}: expected a JSON list of records")
    for i, r in enumerate(records):
        if not isinstance(r, dict) or not {"bench", "params", "metrics"} <= r.keys():
            raise ValueError(f"{source}: record {i} lacks bench/params/metrics")
    return records


def table(records):
    lines = []
    for r in records:
        params = " ".join(f"{k}={v}" for k, v in r["params"].items())
        metrics = " ".join(f"{k}={v:.4g}" if isinstance(v, (int, float)) else f"{k}={v}" for k, v in r["metrics"].items())
        lines.append(f"{r['bench']:<22} {params:<48} {metrics}")
    return "\n".join(lines)


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--build", default="build")
    parser.add_argument("--out", default="out/bench")
    parser.add_argument("--only", default="", help="run only benchmarks whose name contains this")
    args = parser.parse_args()
    build, out = pathlib.Path(args.build).resolve(), pathlib.Path(args.out).resolve()
    out.mkdir(parents=True, exist_ok=True)

    benches = [(n, c) for n, c in discover(build) if args.only in n]
    if not benches:
        print(f"run_benchmarks: no benchmarks found in {build}/bench or scripts/bench_*.py")
        return 0
    failed, all_records = [], []
    for index, (name, command) in enumerate(benches, 1):
        target = out / f"{name}.json"
        command = command + ["--out", str(target)]
        print(f"[{index}/{len(benches)}] {name} ...", flush=True)
        started = time.monotonic()
        result = subprocess.run(command, cwd=ROOT)
        if result.returncode != 0:
            print(f"[{index}/{len(benches)}] {name} FAILED (exit {result.returncode})", flush=True)
            failed.append(name)
            continue
        try:
            all_records += validate(json.loads(target.read_text()), target)
        except (OSError, ValueError) as error:
            print(f"[{index}/{len(benches)}] {name} wrote no valid results: {error}")
            failed.append(name)
            continue
        print(f"[{index}/{len(benches)}] {name} done in {time.monotonic() - started:.1f} s -> {target}", flush=True)
    print()
    print(table(all_records))
    if failed:
        print(f"\nrun_benchmarks: {len(failed)} failed: {', '.join(failed)}")
        return 1
    return 0


if __name__ == "__main__":
    sys.exit(main())
