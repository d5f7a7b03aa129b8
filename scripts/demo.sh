#!/usr/bin/env bash
# The README's demo: a bundled sample groom through coif's pipeline. Outputs land in $2.
set -euo pipefail
coif=${1:-target/release/coif}
out=${2:-out/demo}
mkdir -p "$out"
groom=grooms/seed_200x24cm.hair

echo "== import: $groom"
"$coif" info "$groom"

echo "== export"
"$coif" convert "$groom" "$out/groom.hair"

echo "== a fresh procedural groom (curly, 2,000 strands)"
"$coif" generate -o "$out/curly.hair" --strands 2000 --vertices 24 --style curly --seed 11
"$coif" info "$out/curly.hair"
echo "demo outputs in $out/"
