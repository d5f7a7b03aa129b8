# coif — the two commands a new machine needs:
#   make demo   style a bundled sample groom end to end
#   make test   every test, plus format and lint checks
# Both install what they need first (idempotently) through `make setup`.

SHELL := /bin/bash
export PATH := $(HOME)/.cargo/bin:$(PATH)
CARGO ?= cargo
COIF := target/release/coif
DEMO_OUT ?= out/demo

.PHONY: setup build demo test bench grooms clean

setup: .deps/.setup-done

.deps/.setup-done: scripts/setup.sh
	bash scripts/setup.sh
	touch $@

build: setup
	$(CARGO) build --release --locked

demo: build
	bash scripts/demo.sh $(COIF) $(DEMO_OUT)

test: setup
	$(CARGO) fmt --check
	$(CARGO) clippy --locked --all-targets -- -D warnings
	$(CARGO) test --locked

# Benchmarks print figures for named configurations (never timed tests).
bench: setup
	$(CARGO) bench --locked --bench sim

# Regenerates the sample grooms checked into grooms/ (see grooms/README.md).
grooms: build
	bash scripts/make_grooms.sh $(COIF)

clean:
	$(CARGO) clean
	rm -rf out

# USD export/import: native .usda vs usd-core's .usdc (100,000 x 32 groom; medians of 3 runs).
.PHONY: bench-usd
bench-usd: setup
	$(CARGO) bench --locked --bench usd
