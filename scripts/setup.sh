#!/usr/bin/env bash
# Installs everything coif needs on a fresh Debian 12 machine. Idempotent: each step checks
# before it acts, so `make setup` is cheap once done.
#   - libclang (bindgen for embree4-sys)
#   - Embree 4 shared library, taken from the `embreex` wheel (Debian 12 only ships Embree 3)
#   - a project-local Python venv with usd-core (pxr) for USD interop and checks
set -euo pipefail
cd "$(dirname "$0")/.."
DEPS="$PWD/.deps"
mkdir -p "$DEPS"
EMBREEX_VERSION=4.4.0.post1
USD_CORE_VERSION=26.11

log() { printf 'setup: %s\n' "$*" >&2; }

as_root() { if [ "$(id -u)" = 0 ]; then "$@"; else sudo "$@"; fi; }

# --- Debian packages -------------------------------------------------------------------------
need_pkgs=()
for pkg in libclang-dev unzip; do
  dpkg -s "$pkg" >/dev/null 2>&1 || need_pkgs+=("$pkg")
done
if [ ${#need_pkgs[@]} -gt 0 ]; then
  log "installing Debian packages: ${need_pkgs[*]}"
  as_root apt-get update -qq
  DEBIAN_FRONTEND=noninteractive as_root apt-get install -y -qq "${need_pkgs[@]}" >/dev/null
fi

# --- Embree 4 from the embreex wheel ----------------------------------------------------------
EMBREE_DIR="$DEPS/embree"
if [ ! -e "$EMBREE_DIR/libembree4.so" ]; then
  log "fetching Embree 4 (embreex==$EMBREEX_VERSION wheel)"
  tmp=$(mktemp -d)
  python3 -m pip download --quiet --no-deps --only-binary=:all: -d "$tmp" "embreex==$EMBREEX_VERSION"
  rm -rf "$EMBREE_DIR.partial" && mkdir -p "$EMBREE_DIR.partial"
  unzip -q -j "$tmp"/embreex-*.whl 'embreex.libs/*' -d "$EMBREE_DIR.partial"
  so=$(cd "$EMBREE_DIR.partial" && ls libembree4-*.so.4 | head -n1)
  ln -sf "$so" "$EMBREE_DIR.partial/libembree4.so"
  rm -rf "$EMBREE_DIR" && mv "$EMBREE_DIR.partial" "$EMBREE_DIR"
  rm -rf "$tmp"
fi

# --- Python venv with usd-core -----------------------------------------------------------------
VENV="$DEPS/venv"
if ! "$VENV/bin/python" -c 'import pxr.Usd' >/dev/null 2>&1; then
  log "creating Python venv with usd-core==$USD_CORE_VERSION"
  python3 -m venv "$VENV"
  "$VENV/bin/python" -m pip install --quiet --upgrade pip
  "$VENV/bin/python" -m pip install --quiet "usd-core==$USD_CORE_VERSION"
fi
log "ready (Embree: $EMBREE_DIR, Python: $VENV/bin/python)"
