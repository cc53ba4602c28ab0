#!/usr/bin/env bash
# Trajectory hashes of the scripted expert (and the hold control) on seeds 0..N-1 of every shipped
# simulated task, one line per episode: `<policy> <task> <seed> <outcome> <hash>`. A refactor that
# must not change behaviour compares this output before and after (`diff`).
# Usage: scripts/trajectory-hashes.sh [EPISODES] > hashes.txt   (needs `cargo build --release`)
set -euo pipefail
cd "$(dirname "$0")/.."
episodes="${1:-5}"
bin="${AUTOBIO_BIN:-${CARGO_TARGET_DIR:-target}/release/autobio}"
out="$(mktemp -d)"
trap 'rm -rf "$out"' EXIT
for p in protocols/*/*.toml; do
  # A scene file (shared by protocols with `scene = ..`) is no task.
  if grep -q '^\[scene\]' "$p"; then continue; fi
  for policy in expert hold; do
    dir="$out/$policy/$(basename "$(dirname "$p")")_$(basename "$p" .toml)"
    mkdir -p "$out/$policy"
    if ! "$bin" eval --protocol "$p" --policy "$policy" --episodes "$episodes" --seed 0 --workers 2 \
      --out "$dir" >/dev/null 2>"$dir.err"; then
      echo "$policy $p - refused: $(tail -1 "$dir.err")"
      continue
    fi
    python3 - "$policy" "$dir" <<'PY'
import glob, json, sys
policy, d = sys.argv[1], sys.argv[2]
for f in sorted(glob.glob(f"{d}/*.results.json")):
    r = json.load(open(f))
    for e in r["episodes"]:
        print(policy, r["task_id"], e["seed"], e["outcome"], e["trajectory_hash"])
PY
  done
done
