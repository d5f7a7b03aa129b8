#!/usr/bin/env bash
# Installs the peer renderer of `make bench-peers`, idempotently (optional; not part of
# `make setup`, `make test` or CI): Mitsuba 3 and Dr.Jit from PyPI into .deps/mitsuba-venv, and
# Debian's LLVM 19 runtime for Dr.Jit's llvm backend (LLVM 14 and 15 cannot select the
# `fminimum` its hair kernels use; scripts/bench_peers.py points DRJIT_LIBLLVM_PATH at it).
set -euo pipefail
cd "$(dirname "$0")/.."
MITSUBA_VERSION=3.9.1
DRJIT_VERSION=1.5.0
VENV="$PWD/.deps/mitsuba-venv"
LLVM=/usr/lib/x86_64-linux-gnu/libLLVM-19.so

if [ ! -e "$LLVM" ]; then
  printf 'bench-peers: installing libllvm19\n' >&2
  sudo_cmd=""
  if [ "$(id -u)" -ne 0 ]; then sudo_cmd=sudo; fi
  $sudo_cmd apt-get update -qq && $sudo_cmd apt-get install -y -qq libllvm19
fi

if ! "$VENV/bin/python" -c 'import mitsuba, drjit, numpy' >/dev/null 2>&1; then
  printf 'bench-peers: installing mitsuba==%s, drjit==%s into %s\n' \
    "$MITSUBA_VERSION" "$DRJIT_VERSION" "$VENV" >&2
  python3 -m venv "$VENV"
  "$VENV/bin/python" -m pip install --quiet --upgrade pip
  "$VENV/bin/python" -m pip install --quiet "mitsuba==$MITSUBA_VERSION" "drjit==$DRJIT_VERSION" numpy
fi
