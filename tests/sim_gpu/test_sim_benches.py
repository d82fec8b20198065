"""The simulator benchmarks run (`make bench` is not part of `make test`, so a change that breaks
one would otherwise go unseen): bench_sim_cpu and bench_sim_vulkan in their --quick form write
their JSON records, and each pool is stepped by the method its sweep names (a scene that leaves
fluid.solver out gets the schema's default, which the Vulkan backend does not run)."""
import json
import subprocess

import pytest


def run_bench(build_dir, name, out):
    path = build_dir / "bench" / name
    # Both are built with everything else (sim_gpu/CMakeLists.txt): a missing one is a failure.
    assert path.exists(), f"{path} not built"
    result = subprocess.run([str(path), "--quick", "--out", str(out)], capture_output=True, text=True, timeout=300)
    assert result.returncode == 0, result.stderr
    return json.loads(out.read_text())


@pytest.mark.slow
def test_bench_sim_cpu_steps_each_pool_with_its_named_method(build_dir, tmp_path):
    records = run_bench(build_dir, "bench_sim_cpu", tmp_path / "cpu.json")
    pools = [r for r in records if r["params"]["sweep"] == "pool"]
    for solver in ("wcsph", "dfsph"):
        threads = {r["params"]["threads"] for r in pools if r["params"]["solver"] == solver}
        assert threads == {1, 2}, f"{solver}: pools on {threads} threads"
        scaling = [r for r in records if r["params"]["sweep"] == "scaling" and r["params"]["solver"] == solver]
        assert len(scaling) == 1 and scaling[0]["metrics"]["speedup_2_threads"] > 0
    # The wcsph pools have no pressure solve, the dfsph pools iterate theirs.
    for r in pools:
        iterations = r["metrics"]["density_iterations_per_step"]
        assert (iterations == 0) == (r["params"]["solver"] == "wcsph"), r
    assert all(r["metrics"]["steps_per_s"] > 0 for r in records if "steps_per_s" in r["metrics"])


@pytest.mark.slow
def test_bench_sim_vulkan_runs_its_pools_and_figures(build_dir, tmp_path):
    records = run_bench(build_dir, "bench_sim_vulkan", tmp_path / "vulkan.json")
    assert {r["params"]["sweep"] for r in records} == {"pool", "pool_dfsph", "fig6b", "fig6c"}
    assert all(r["params"]["backend"] == "vulkan" and r["metrics"]["steps_per_s"] > 0 for r in records)
    # Each pool ran the method its sweep names, and says what a step asked of the device and the
    # host: a frame of fluid steps is one submission and one wait (a step with bodies two, around
    # the host's body integration); the incompressible solver's iterations are indirect
    # dispatches, and it iterated.
    for r in records:
        m = r["metrics"]
        assert r["params"]["solver"] == ("dfsph" if r["params"]["sweep"] == "pool_dfsph" else "wcsph"), r
        assert m["dispatches_per_step"] > 0 and m["barriers_per_step"] > 0, r
        round_trips = 2 if r["params"]["body_particles"] > 0 else 1
        assert m["host_waits_per_step"] == m["submissions_per_step"] <= round_trips, r
        assert (m["indirect_dispatches_per_step"] > 0) == (r["params"]["solver"] == "dfsph"), r
        if r["params"]["solver"] == "dfsph":
            assert m["density_iterations_per_step"] >= 2 and "vulkan_over_cpu" in m, r
