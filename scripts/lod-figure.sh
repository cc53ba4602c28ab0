#!/usr/bin/env bash
# Regenerates docs/img/lod-side-by-side.png: frames of one thermal-cycler episode drawn from the
# same recorded states with the full meshes (left) and the simplified ones (right), and prints the
# PSNR between the two levels over the whole episode, per camera.
# Usage: scripts/lod-figure.sh [path/to/autobio]   (default: target/release/autobio)
set -euo pipefail
BIN=${1:-target/release/autobio}
WORK=$(mktemp -d)
trap 'rm -rf "$WORK"' EXIT
"$BIN" eval --protocol protocols/thermal_cycler/close_lid.toml --episodes 1 --seed 0 2>/dev/null \
  --record --out "$WORK/run" >/dev/null
REC=$(ls "$WORK"/run/*.mcap)
"$BIN" replay "$REC" --render --detail full --out "$WORK/full.mcap" --png "$WORK/full" >/dev/null
"$BIN" replay "$REC" --render --detail simplified --out "$WORK/simple.mcap" --png "$WORK/simple" >/dev/null
rows=()
for f in table_front_00100 arm_wrist_00100 table_front_00300 arm_wrist_00300; do
  ffmpeg -loglevel error -y -i "$WORK/full/$f.png" -i "$WORK/simple/$f.png" \
    -filter_complex "hstack,scale=896:-1:flags=neighbor" "$WORK/row_$f.png"
  rows+=(-i "$WORK/row_$f.png")
done
ffmpeg -loglevel error -y "${rows[@]}" -filter_complex vstack=inputs=4 docs/img/lod-side-by-side.png
for c in table_front arm_wrist; do
  printf '%-12s ' "$c"
  ffmpeg -framerate 10 -pattern_type glob -i "$WORK/full/${c}_*.png" \
    -framerate 10 -pattern_type glob -i "$WORK/simple/${c}_*.png" -lavfi psnr -f null - 2>&1 \
    | grep -o 'average:[0-9.]* min:[0-9.]*'
done
