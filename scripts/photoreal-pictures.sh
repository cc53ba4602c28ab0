#!/usr/bin/env bash
# The pictures in docs/photoreal.md: five tasks' seed-0 start from their task cameras, the
# rasteriser's frames above Blender's (Cycles, 32 samples, denoised), from `autobio render
# --renderer blender` (its view from above dropped: Blender draws the task cameras only).
# Run after `make setup`; writes docs/img/photoreal-<task>.png.
set -euo pipefail
cd "$(dirname "$0")/.."
autobio() {
  if [ -n "${AUTOBIO:-}" ]; then "$AUTOBIO" "$@"; else cargo run --release --quiet -- "$@"; fi
}
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
for p in thermal_cycler/close_lid tube/transfer thermal_mixer/set_parameters \
  centrifuge/insert_symmetric pipette/aspirate; do
  name=$(echo "$p" | tr '/' '-')
  autobio render "protocols/$p.toml" --seed 0 --size 320x240 --renderer blender --samples 32 \
    --png "$tmp/$name.png" >/dev/null
  .deps/python-env/bin/python - "$tmp/$name.png" "docs/img/photoreal-$name.png" <<'PY'
import sys
from PIL import Image
sheet, out = sys.argv[1:]
im = Image.open(sheet)
h = im.size[1] // 2
cameras = (im.size[0] // 320 - 1) * 320  # the raster row ends with the view from above
grid = Image.new("RGB", (cameras, 2 * h))
grid.paste(im.crop((0, 0, cameras, h)), (0, 0))
grid.paste(im.crop((0, h, cameras, 2 * h)), (0, h))
grid.save(out, optimize=True)
PY
done
