#!/usr/bin/env bash
# The pictures in docs/robustness.md: for each perturbation dimension that shows in a frame, one
# seed of the tube transfer drawn clean, at strength 1 and at strength 2 (rows, top to bottom;
# the bench camera, the wrist camera and the view from above, left to right), from `autobio
# render --perturb`. Run after `make setup`; writes docs/img/perturb-<dimension>.png.
set -euo pipefail
cd "$(dirname "$0")/.."
autobio() {
  if [ -n "${AUTOBIO:-}" ]; then "$AUTOBIO" "$@"; else cargo run --release --quiet -- "$@"; fi
}
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
for d in light material camera noise robot_start layout distractors; do
  for s in 1 2; do
    autobio render protocols/tube/transfer.toml --seed 3 --size 160x120 \
      --perturb "$d:$s" --png "$tmp/$d-$s.png" >/dev/null
  done
  .deps/python-env/bin/python - "$tmp/$d-1.png" "$tmp/$d-2.png" "docs/img/perturb-$d.png" <<'PY'
import sys
from PIL import Image
one, two, out = sys.argv[1:]
a, b = Image.open(one), Image.open(two)
w, h = a.size[0], a.size[1] // 2
grid = Image.new("RGB", (w, 3 * h))
grid.paste(a.crop((0, 0, w, 2 * h)), (0, 0))
grid.paste(b.crop((0, h, w, 2 * h)), (0, 2 * h))
grid.save(out, optimize=True)
PY
done
