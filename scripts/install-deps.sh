#!/usr/bin/env bash
# Installs exactly what hapfluid needs and is missing: Debian packages through apt, Python
# packages into the project venv (.venv). Idempotent and quiet when nothing is missing, so every
# make target can call it. Nothing is fetched from anywhere but Debian's archive and PyPI.
#
#   scripts/install-deps.sh            core: build, test, run
#   scripts/install-deps.sh hil        core + what the QEMU hardware-in-the-loop suite needs
#   scripts/install-deps.sh bench      core + SPlisHSPlasH (PyPI wheel), the benchmarks' reference solver
#   scripts/install-deps.sh fuzz       core + clang with libFuzzer and the symbolizer (make fuzz)
#   scripts/install-deps.sh deb        core + mmdebstrap, for the package check in a Debian chroot (make deb)
set -euo pipefail

here="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
group="${1:-core}"

debian_core=(
  build-essential cmake ninja-build pkg-config git
  libtomlplusplus-dev libcli11-dev nlohmann-json3-dev googletest libgtest-dev libgmock-dev
  libvulkan-dev libvulkan-volk-dev mesa-vulkan-drivers vulkan-validationlayers vulkan-tools
  glslang-tools spirv-tools
  libglfw3-dev libpng-dev libstb-dev libglm-dev xvfb xauth
  libusb-1.0-0-dev libhidapi-dev can-utils libsystemd-dev systemd
  rt-tests strace
  python3-venv
  chromium
)
debian_hil=(qemu-system-x86 busybox-static cpio kmod udev)
# clang-14 (via clang) compiles the fuzzing build, libclang-rt-14-dev holds libFuzzer and the
# sanitizer runtimes, llvm-14 the llvm-symbolizer that turns sanitizer reports into file:line.
debian_fuzz=(clang libclang-rt-14-dev llvm-14)
# A fresh Debian 12 root to install the package into (make deb); dpkg-shlibdeps, which CPack uses
# for the package's library dependencies, comes with build-essential's dpkg-dev.
debian_deb=(mmdebstrap)
# Python: the hapfluid package (scripts/pyproject.toml) with its extras, every version pinned by
# scripts/constraints.txt.
python_extras=test

want=("${debian_core[@]}")
[ "$group" = hil ] && want+=("${debian_hil[@]}")
[ "$group" = fuzz ] && want+=("${debian_fuzz[@]}")
[ "$group" = deb ] && want+=("${debian_deb[@]}")
case "$group" in
  core|hil|fuzz|deb) ;;
  bench) python_extras=test,bench ;;
  *) echo "install-deps: unknown group '$group' (core, hil, bench, fuzz or deb)" >&2; exit 2 ;;
esac

missing=()
for p in "${want[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done

if [ ${#missing[@]} -gt 0 ]; then
  if [ "$(id -u)" != 0 ]; then
    echo "install-deps: missing Debian packages: ${missing[*]}" >&2
    echo "install-deps: run as root (or: sudo apt-get install ${missing[*]})" >&2
    exit 1
  fi
  echo "install-deps: installing Debian packages: ${missing[*]}"
  export DEBIAN_FRONTEND=noninteractive
  # Another apt (unattended-upgrades, a second make in another checkout) may hold the dpkg lock:
  # wait for it rather than fail the build.
  apt=(apt-get -o DPkg::Lock::Timeout=600)
  # A stale or empty package list makes apt say "unable to locate": refresh once, then install.
  if ! "${apt[@]}" install -y -q --no-install-recommends "${missing[@]}" >/tmp/hapfluid-apt.log 2>&1; then
    # The lock timeout covers dpkg's locks, not the package lists' lock that update takes: wait
    # for that one here (10 min at most), and fail at once on any other error.
    for attempt in $(seq 60); do
      "${apt[@]}" update -q >/tmp/hapfluid-apt-update.log 2>&1 && break
      if ! grep -q "Could not get lock" /tmp/hapfluid-apt-update.log || [ "$attempt" = 60 ]; then
        cat /tmp/hapfluid-apt-update.log >&2
        exit 1
      fi
      sleep 10
    done
    "${apt[@]}" install -y -q --no-install-recommends "${missing[@]}" >/tmp/hapfluid-apt.log 2>&1 \
      || { tail -n 30 /tmp/hapfluid-apt.log >&2; echo "install-deps: apt-get install failed (log: /tmp/hapfluid-apt.log)" >&2; exit 1; }
  fi
fi

venv="$here/.venv"
if [ ! -x "$venv/bin/python" ]; then
  echo "install-deps: creating Python venv in $venv"
  python3 -m venv "$venv" || /usr/bin/python3 -m venv "$venv"
fi
# Installed when the venv lacks what this checkout's pyproject and constraints ask for: a stamp of
# both (the package's entry points live in its install metadata), then each requirement at its pin.
project="$here/scripts"
stamp="$venv/hapfluid-install.stamp"
want_stamp="$(cat "$project/pyproject.toml" "$project/constraints.txt" | sha256sum | cut -c1-16) $project"
if [ "$(cat "$stamp" 2>/dev/null)" != "$want_stamp" ] \
    || ! "$venv/bin/python" - "$project" "$python_extras" <<'PY'
import pathlib, re, sys, tomllib
from importlib import metadata

project, extras = pathlib.Path(sys.argv[1]), sys.argv[2].split(",")
norm = lambda name: re.sub(r"[-_.]+", "-", name).lower()
pins = {norm(line.split("==")[0]): line.split("==")[1].strip()
        for line in (project / "constraints.txt").read_text().split("\n") if line.strip() and not line.startswith("#")}
spec = tomllib.loads((project / "pyproject.toml").read_text())["project"]
wanted = ["hapfluid", *spec["dependencies"], *(r for e in extras for r in spec["optional-dependencies"][e])]
for requirement in wanted:
    name = norm(re.match(r"[A-Za-z0-9._-]+", requirement).group())
    try:
        version = metadata.version(name)
    except metadata.PackageNotFoundError:
        sys.exit(1)
    if name in pins and version != pins[name]:
        sys.exit(1)
PY
then
  echo "install-deps: installing the hapfluid Python package [$python_extras] into .venv (pins: scripts/constraints.txt)"
  # The constraints reach pip's isolated build environment too (setuptools, wheel) through PIP_CONSTRAINT.
  PIP_CONSTRAINT="$project/constraints.txt" "$venv/bin/python" -m pip install -q --disable-pip-version-check \
    -e "$project[$python_extras]"
  echo "$want_stamp" > "$stamp"
fi
