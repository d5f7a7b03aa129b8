#!/usr/bin/env bash
# The README's demo, coif's main job on a bundled sample groom:
#   import → style (a perm on curler rods) → settle → export USD + Alembic → preview PNG.
# Outputs land in $2 (default out/demo).
set -euo pipefail
coif=${1:-target/release/coif}
out=${2:-out/demo}
mkdir -p "$out"
groom=grooms/seed_100x48cm.hair
recipe=grooms/recipes/perm_scene3.toml

echo "== import: $groom"
"$coif" info "$groom"

echo "== style: $recipe (wet, wind on rods, lotion, neutralise, dry, release, settle)"
"$coif" style "$recipe" --groom "$groom" -o "$out/permed.usda"

echo "== export: Alembic (and Unreal's groom conventions)"
"$coif" convert "$out/permed.usda" "$out/permed.abc"
"$coif" convert --unreal "$out/permed.usda" "$out/permed_unreal.abc"
"$coif" info "$out/permed.abc"

echo "== preview"
"$coif" render "$out/permed.usda" -o "$out/preview.png" --view three-quarter --res 480x360 --spp 32 --width-scale 6
echo "demo outputs in $out/: permed.usda, permed.abc, permed_unreal.abc, preview.png"
