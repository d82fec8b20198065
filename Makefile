# hapfluid — the only entry point a user needs.
#   make          install what is missing, build
#   make test     ... and run every test (ctest + pytest), with their summaries
#   make check    ... and run the fast tier only (no whole-scene validation, live stack or QEMU)
#   make run      ... and run the main job (SCENE=<name> for another scene)
#   make bench    ... and run every benchmark, JSON under out/bench/ (installs SPlisHSPlasH for the comparison)
#   make fuzz     fuzz every reader of untrusted input (clang, libFuzzer, ASan+UBSan in build-fuzz/),
#                 RUNS executions per target (default 1000000), JSON in out/fuzz/fuzz.json
#   make hil      ... and run the QEMU hardware-in-the-loop suite (KERNEL=rt: PREEMPT_RT kernel)
#   make install  install binaries, config, systemd units and the Python tools (PREFIX=/usr/local)
#   make deb      ... and build the Debian package (out/deb/) and check it in a fresh Debian 12 chroot:
#                 install, systemd-analyze verify, the default scene live, remove (NOCHECK=1: build only)
#   make clean    remove build/, build-fuzz/ and out/
SHELL := /bin/bash
BUILD ?= build
FUZZ_BUILD ?= build-fuzz
RUNS ?= 1000000
BUILD_TYPE ?= RelWithDebInfo
PREFIX ?= /usr/local
SCENE ?= spoon_stirring
DURATION ?=
VENV := .venv
PY := $(VENV)/bin/python
JOBS ?= $(shell nproc)
KERNEL ?= default

.PHONY: all deps build test check run bench fuzz install deb clean hil

all: build

deps:
	@bash scripts/install-deps.sh

$(BUILD)/build.ninja: CMakeLists.txt | deps
	@cmake -S . -B $(BUILD) -G Ninja -DCMAKE_BUILD_TYPE=$(BUILD_TYPE) -DCMAKE_INSTALL_PREFIX=$(PREFIX) >/dev/null

build: deps $(BUILD)/build.ninja
	@cmake --build $(BUILD) -j $(JOBS)

test: build
	@bash scripts/run-tests.sh $(BUILD)

check: build
	@bash scripts/run-tests.sh $(BUILD) --fast

run: build
	@$(PY) -m hapfluid run --build $(BUILD) --scene $(SCENE) $(if $(DURATION),--duration $(DURATION))

bench: build
	@bash scripts/install-deps.sh bench
	@$(PY) scripts/run_benchmarks.py --build $(BUILD) --out out/bench

# Its own build folder: clang instruments every library for libFuzzer (CMake option HAPFLUID_FUZZ).
fuzz: deps
	@bash scripts/install-deps.sh fuzz
	@cmake -S . -B $(FUZZ_BUILD) -G Ninja -DCMAKE_BUILD_TYPE=RelWithDebInfo -DCMAKE_C_COMPILER=clang \
	  -DCMAKE_CXX_COMPILER=clang++ -DHAPFLUID_FUZZ=ON >/dev/null
	@cmake --build $(FUZZ_BUILD) --target fuzzers -j $(JOBS)
	@$(PY) scripts/run_fuzz.py --build $(FUZZ_BUILD) --out out/fuzz --runs $(RUNS)

install: build
	@cmake --install $(BUILD) --prefix $(PREFIX)

# The package carries the build folder's binaries, installed under /usr (cmake/packaging.cmake).
deb: build
	@bash scripts/install-deps.sh deb
	@rm -f out/deb/hapfluid_*.deb
	@cd $(BUILD) && cpack -G DEB -B $(CURDIR)/out/deb >/dev/null
	@echo "deb: $$(ls out/deb/hapfluid_*.deb)"
	@$(if $(NOCHECK),true,$(PY) scripts/check_deb.py --deb $$(ls out/deb/hapfluid_*.deb) --out out/deb)

hil: build
	@$(PY) tests/hil-kernel/hil.py --build $(BUILD) --kernel $(KERNEL)

clean:
	rm -rf $(BUILD) $(FUZZ_BUILD) out
