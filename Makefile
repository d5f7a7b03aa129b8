# coif — the two commands a new machine needs:
#   make demo   style a bundled sample groom end to end
#   make test   every test, plus format and lint checks
# Both install what they need first (idempotently) through `make setup`.

SHELL := /bin/bash
export PATH := $(HOME)/.cargo/bin:$(PATH)
CARGO ?= cargo
COIF := target/release/coif
DEMO_OUT ?= out/demo

.PHONY: setup build demo test bench grooms golden clean

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

# Regenerates the sample grooms checked into grooms/ (see grooms/README.md).
grooms: build
	bash scripts/make_grooms.sh $(COIF)

# Re-renders the renderer's golden images in tests/golden/ (view them before committing).
golden: setup
	COIF_UPDATE_GOLDEN=1 $(CARGO) test --locked --test render_golden canonical_scenes

clean:
	$(CARGO) clean
	rm -rf out
