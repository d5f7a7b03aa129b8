#!/usr/bin/env bash
# Installs Blender-as-a-Python-module (bpy, ~370 MB) into its own venv, idempotently. `make test`
# (Blender's importers read coif's files), `make check-blender` and `make bench-peers` (Cycles)
# need it; `make demo` does not.
set -euo pipefail
cd "$(dirname "$0")/.."
BPY_VERSION=5.0.1
VENV="$PWD/.deps/bpy-venv"
if ! "$VENV/bin/python" -c 'import bpy' >/dev/null 2>&1; then
  printf 'setup-bpy: installing bpy==%s into %s\n' "$BPY_VERSION" "$VENV" >&2
  python3 -m venv "$VENV"
  "$VENV/bin/python" -m pip install --quiet --upgrade pip
  "$VENV/bin/python" -m pip install --quiet "bpy==$BPY_VERSION"
fi
