#!/usr/bin/env bash
# Regenerates grooms/*.hair from fixed seeds; the outputs are byte-identical on every machine.
set -euo pipefail
coif=${1:-target/release/coif}
cd "$(dirname "$0")/.."
# The seed papers' scenes 1 and 2: 200 strands x 24 cm, one vertex per 3 cm.
"$coif" generate -o grooms/seed_200x24cm.hair --strands 200 --length 0.24 --vertices 9 --seed 1
# Scene 3 (perm): 100 strands x 48 cm, one vertex per 3 cm.
"$coif" generate -o grooms/seed_100x48cm.hair --strands 100 --length 0.48 --vertices 17 --seed 3
# A small curly groom (imports at rest as curly) and a wavy one, for tests and demos.
"$coif" generate -o grooms/sample_curly.hair --strands 300 --length 0.2 --vertices 32 --style curly \
  --curl-radius 0.008 --curl-pitch 0.025 --seed 5
"$coif" generate -o grooms/sample_wavy.hair --strands 300 --length 0.3 --vertices 24 --style wavy --seed 7
