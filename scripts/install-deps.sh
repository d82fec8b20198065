#!/usr/bin/env bash
# Installs exactly what hapfluid needs and is missing: Debian packages through apt, Python
# packages into the project venv (.venv). Idempotent and quiet when nothing is missing, so every
# make target can call it. Nothing is fetched from anywhere but Debian's archive and PyPI.
#
#   scripts/install-deps.sh            core: build, test, run
#   scripts/install-deps.sh hil        core + what the QEMU hardware-in-the-loop suite needs
#   scripts/install-deps.sh bench      core + SPlisHSPlasH (PyPI wheel), the benchmarks' reference solver
#   scripts/install-deps.sh fuzz       core + clang with libFuzzer and the symbolizer (make fuzz)
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
)
debian_hil=(qemu-system-x86 busybox-static cpio kmod udev)
# clang-14 (via clang) compiles the fuzzing build, libclang-rt-14-dev holds libFuzzer and the
# sanitizer runtimes, llvm-14 the llvm-symbolizer that turns sanitizer reports into file:line.
debian_fuzz=(clang libclang-rt-14-dev llvm-14)
python_packages=(pytest numpy matplotlib python-can cantools hypothesis tomli-w)
# Only bench_splishsplash.py uses it; pinned so that its scene format and log stay what we parse.
python_bench=(pysplishsplash==2.19.0)

want=("${debian_core[@]}")
[ "$group" = hil ] && want+=("${debian_hil[@]}")
[ "$group" = fuzz ] && want+=("${debian_fuzz[@]}")
case "$group" in
  core|hil|fuzz) ;;
  bench) python_packages+=("${python_bench[@]}") ;;
  *) echo "install-deps: unknown group '$group' (core, hil, bench or fuzz)" >&2; exit 2 ;;
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
  # A stale or empty package list makes apt say "unable to locate": refresh once, then install.
  if ! apt-get install -y -q --no-install-recommends "${missing[@]}" >/tmp/hapfluid-apt.log 2>&1; then
    apt-get update -q >/tmp/hapfluid-apt-update.log 2>&1 || { cat /tmp/hapfluid-apt-update.log >&2; exit 1; }
    apt-get install -y -q --no-install-recommends "${missing[@]}" >/tmp/hapfluid-apt.log 2>&1 \
      || { tail -n 30 /tmp/hapfluid-apt.log >&2; echo "install-deps: apt-get install failed (log: /tmp/hapfluid-apt.log)" >&2; exit 1; }
  fi
fi

venv="$here/.venv"
if [ ! -x "$venv/bin/python" ]; then
  echo "install-deps: creating Python venv in $venv"
  python3 -m venv "$venv" || /usr/bin/python3 -m venv "$venv"
fi
pymissing=()
for p in "${python_packages[@]}"; do
  name="${p%%==*}"
  if [ "$name" = "$p" ]; then
    "$venv/bin/python" -m pip show -q "$p" >/dev/null 2>&1 || pymissing+=("$p")
  else
    # Pinned: the installed version must be the pin's.
    have="$("$venv/bin/python" -m pip show "$name" 2>/dev/null | sed -n 's/^Version: //p' || true)"
    [ "$have" = "${p#*==}" ] || pymissing+=("$p")
  fi
done
if [ ${#pymissing[@]} -gt 0 ]; then
  echo "install-deps: installing Python packages into .venv: ${pymissing[*]}"
  "$venv/bin/python" -m pip install -q --disable-pip-version-check "${pymissing[@]}"
fi
