#!/usr/bin/env bash
# Renders this folder's references with pbrt-v4 (PBRT: its binary; see README.md for the build).
set -euo pipefail
cd "$(dirname "$0")"
PBRT=${PBRT:-pbrt}
SPP=${SPP:-4096}
mkdir -p references
: > references/timings.txt
for scene in materials bump-alpha shapes motion hair measured spherical goniometric projection subsurface realistic realistic-wide portal alpha-light image-lights procedural differentials ewa displacement ptex invisible-light portal-spectrum projective-env subsurface-textured; do
    start=$(date +%s.%N)
    "$PBRT" --quiet --nthreads 2 --spp "$SPP" --seed 7 --outfile "references/$scene.exr" "$scene.pbrt"
    end=$(date +%s.%N)
    printf "%s %s spp %.1f s\n" "$scene" "$SPP" "$(echo "$end - $start" | bc)" | tee -a references/timings.txt
done
