#!/usr/bin/env bash
# Renders the volpath references of the scene suite (run from the repository root):
#   bash pbrt-scenes/references/render.sh [SPP]
# Each EXR records its spp, time, integrator and seed in its metadata.
set -euo pipefail
spp=${1:-2048}
for scene in pbrt-scenes/*.pbrt; do
  name=$(basename "$scene" .pbrt)
  [ "$name" = default ] && continue
  # Light reaches the wax only through refraction: twice the samples for a comparable noise level.
  n=$spp; [ "$name" = wax-small-light ] && n=$((2 * spp))
  cargo run --release --quiet -- render "$scene" --integrator volpath --spp "$n" --seed 7 --quiet \
    --outfile "pbrt-scenes/references/$name.exr"
  echo "$name done"
done
