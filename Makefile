# coif — the two commands a new machine needs:
#   make demo   style a bundled sample groom end to end
#   make test   every test, plus format and lint checks
# Both install what they need first (idempotently) through `make setup`.

SHELL := /bin/bash
export PATH := $(HOME)/.cargo/bin:$(PATH)
CARGO ?= cargo
COIF := target/release/coif
DEMO_OUT ?= out/demo

.PHONY: setup setup-bpy build demo test bench grooms golden clean check-blender fuzz-alembic fuzz-usdc

setup: .deps/.setup-done

setup-bpy:
	bash scripts/check_blender_setup.sh

.deps/.setup-done: scripts/setup.sh
	bash scripts/setup.sh
	touch $@

build: setup
	$(CARGO) build --release --locked

demo: build
	bash scripts/demo.sh $(COIF) $(DEMO_OUT)

# The tests include Blender's own importers reading coif's files (tests/blender_grooms.rs), so
# `make test` installs bpy too (idempotent: a no-op once `import bpy` works).
test: setup setup-bpy
	$(CARGO) fmt --check
	$(CARGO) clippy --locked --all-targets -- -D warnings
	@# The fuzz targets build beside the test suite, on the cores its single-threaded tests leave idle.
	$(MAKE) -j2 test-suite fuzz-build
	$(MAKE) fuzz-smoke

test-suite:
	$(CARGO) test --locked

# Benchmarks print figures for named configurations (never timed tests).
bench: setup
	$(CARGO) bench --locked --bench sim

# Regenerates the sample grooms checked into grooms/ (see grooms/README.md).
grooms: build
	bash scripts/make_grooms.sh $(COIF)

# Blender's own Alembic importer (bpy, ~370 MB in .deps/bpy-venv) opens a static and an animated
# file written by coif; counts, positions and radii must match. Then the blender_grooms tests run
# with bpy: styled and animated-converted grooms against Blender's own (`make test` runs those too).
check-blender: setup setup-bpy
	$(CARGO) run --release --locked --example alembic_check_files -- out/check-blender
	$(CARGO) run --release --locked -- convert tests/data/blender_groom.abc out/check-blender/blender_groom.abc
	$(CARGO) run --release --locked -- convert tests/data/blender_groom.usda out/check-blender/blender_groom_usd.abc
	.deps/bpy-venv/bin/python scripts/check_blender.py out/check-blender
	@# The tests that compare Blender's import of coif's files with its own (skipped without bpy).
	COIF_REQUIRE_BPY=1 $(CARGO) test --locked --test blender_grooms in_blender

# Fuzzing (cargo-fuzz, installed by scripts/fuzz_setup.sh if missing; libFuzzer needs nightly
# flags, which RUSTC_BOOTSTRAP=1 unlocks on the stable toolchain). `make fuzz` runs every target
# for FUZZ_RUNS executions, one after the other, from its seeds in fuzz/seeds/TARGET plus the
# corpus it grew before (fuzz/corpus/TARGET, not in git), with memory and time limits. A crash,
# allocation over the limit or time-out leaves its input in fuzz/artifacts/TARGET and stops.
# `make fuzz-smoke` (part of `make test`) runs 10^5 executions of each target.
# No sanitizer by default: every parser is safe Rust (the readers' only unsafe code maps the input
# file and gives a huge-page hint, neither reached from a fuzz target), so AddressSanitizer finds
# nothing a panic would not, and it runs 30-50x slower (recipe: 110-180 executions a second
# against 5,500), a day per target for 10^7. `make fuzz FUZZ_SANITIZER=address` still runs it.
FUZZ_TARGETS := hair_reader usda_reader usdc_reader alembic_reader obj_reader recipe manifest
FUZZ_RUNS ?= 10000000
FUZZ_SANITIZER ?= none
FUZZ_FLAGS = -runs=$(FUZZ_RUNS) -max_len=65536 -rss_limit_mb=2048 -malloc_limit_mb=2048 -timeout=10
.PHONY: fuzz fuzz-build fuzz-smoke test-suite
fuzz: fuzz-build
	set -e; for target in $(FUZZ_TARGETS); do \
		mkdir -p fuzz/corpus/$$target; \
		(cd fuzz && RUSTC_BOOTSTRAP=1 cargo fuzz run -s $(FUZZ_SANITIZER) $$target corpus/$$target seeds/$$target -- $(FUZZ_FLAGS)); \
	done
fuzz-build:
	bash scripts/fuzz_setup.sh
	cd fuzz && RUSTC_BOOTSTRAP=1 cargo fuzz build -s $(FUZZ_SANITIZER)
fuzz-smoke:
	$(MAKE) fuzz FUZZ_RUNS=100000
fuzz-alembic:
	$(MAKE) fuzz FUZZ_TARGETS=alembic_reader
fuzz-usdc:
	$(MAKE) fuzz FUZZ_TARGETS=usdc_reader
# Re-renders the renderer's golden images in tests/golden/ (view them before committing).
golden: setup
	COIF_UPDATE_GOLDEN=1 $(CARGO) test --locked --test render_golden canonical_scenes

clean:
	$(CARGO) clean
	rm -rf out

# USD export/import: native .usda vs usd-core's .usdc (100,000 x 32 groom; medians of 3 runs).
# Optional: coif's Chiang lobe against Mitsuba 3's hair BSDF and Cycles' Principled Hair (Chiang)
# at equal noise (installs Mitsuba into .deps/mitsuba-venv and bpy into .deps/bpy-venv; never part
# of `make test`). BENCH_PEERS_ARGS passes options, e.g. --runs 5 or --cycles-python none.
.PHONY: bench-peers
bench-peers: setup
	bash scripts/peers_setup.sh
	$(MAKE) setup-bpy
	$(CARGO) build --release --locked
	.deps/mitsuba-venv/bin/python scripts/bench_peers.py --coif target/release/coif \
		--cycles-python .deps/bpy-venv/bin/python --out out/bench-peers $(BENCH_PEERS_ARGS)

.PHONY: bench-usd
bench-usd: setup
	$(CARGO) bench --locked --bench usd
