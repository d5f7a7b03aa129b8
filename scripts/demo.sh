#!/usr/bin/env bash
# The README's demo, coif's main job on a production-size groom:
#   a generated full head (30,000 strands) → a perm on 24 curler rods, simulated on 500 guides
#   spread over the scalp and interpolated to every strand → settle → USD + Alembic → preview PNG.
# Outputs land in $2 (default out/demo).
set -euo pipefail
coif=${1:-target/release/coif}
out=${2:-out/demo}
mkdir -p "$out"
groom=$out/head.hair
recipe=grooms/recipes/perm_full_head.toml

echo "== import: a generated full head"
"$coif" generate -o "$groom" --strands 30000 --vertices 32 --length 0.24 --seed 21
"$coif" info "$groom"

echo "== style: $recipe on 500 guides (wet, wind on rods, lotion, neutralise, dry, release, settle)"
"$coif" style "$recipe" --groom "$groom" --guides 500 -o "$out/permed.usda"

echo "== export: Alembic (and Unreal's groom conventions)"
"$coif" convert "$out/permed.usda" "$out/permed.abc"
"$coif" convert --unreal "$out/permed.usda" "$out/permed_unreal.abc"
"$coif" info "$out/permed.abc"

echo "== preview"
"$coif" render "$out/permed.usda" -o "$out/preview.png" --view three-quarter --res 480x360 --spp 16 --width-scale 2.5
echo "demo outputs in $out/: permed.usda, permed.abc, permed_unreal.abc, preview.png"
