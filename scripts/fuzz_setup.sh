#!/usr/bin/env bash
# Installs cargo-fuzz for `make fuzz` if it is missing (idempotent; CI and new machines start bare).
set -euo pipefail
export PATH="$HOME/.cargo/bin:$PATH"
if ! command -v cargo-fuzz >/dev/null; then
    cargo install cargo-fuzz --locked
fi
