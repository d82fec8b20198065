#!/usr/bin/env bash
# Runs every test: GoogleTest suites under ctest, then the Python suites under pytest. Both
# print their own closing summary; the script fails if either fails. pytest's exit code 5
# ("no tests collected") is not a failure of the build: it is reported and passes.
#
#   run-tests.sh [BUILD] [--fast]
# --fast (`make check`): the fast tier, without the ctest label `slow` and the pytest marker
# `slow` (whole-scene validation, the live stack, the QEMU guest).
set -uo pipefail
here="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
build=build
ctest_tier=()
pytest_tier=()
for arg in "$@"; do
  case "$arg" in
    --fast) ctest_tier=(-LE slow); pytest_tier=(-m "not slow") ;;
    -*) echo "run-tests: unknown option $arg (--fast)" >&2; exit 2 ;;
    *) build="$arg" ;;
  esac
done
case "$build" in /*) ;; *) build="$here/$build" ;; esac
cd "$here"

# Every test stops its writers cleanly: a segment a test leaves in /dev/shm is a failure (a live
# run's processes must leave nothing behind either).
shm_before="$(ls /dev/shm 2>/dev/null | grep '^hapfluid' | sort)"

echo "== C/C++ tests (ctest) =="
# One test at a time: several suites check real-time behaviour (1 kHz loops, watchdogs) across
# processes, and a neighbour test saturating the other core would only measure the machine.
ctest --test-dir "$build" --output-on-failure -j 1 --timeout 600 ${ctest_tier[@]+"${ctest_tier[@]}"}
ctest_rc=$?

echo "== Python tests (pytest) =="
HAPFLUID_BUILD="$build" "$here/.venv/bin/python" -m pytest -q -p no:cacheprovider ${pytest_tier[@]+"${pytest_tier[@]}"} tests
py_rc=$?
if [ "$py_rc" -eq 5 ]; then
  echo "pytest: no Python tests were collected"
  py_rc=0
fi

shm_left="$(comm -13 <(echo "$shm_before") <(ls /dev/shm 2>/dev/null | grep '^hapfluid' | sort))"
shm_rc=0
if [ -n "$shm_left" ]; then
  echo "== shared memory left in /dev/shm by the tests (a writer not closed): =="
  echo "$shm_left"
  shm_rc=1
fi

echo "== summary: ctest exit $ctest_rc, pytest exit $py_rc, leftover segments $(echo -n "$shm_left" | grep -c .) =="
[ "$ctest_rc" -eq 0 ] && [ "$py_rc" -eq 0 ] && [ "$shm_rc" -eq 0 ]
