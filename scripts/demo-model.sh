#!/usr/bin/env bash
# The model-server part of `make demo`: the reference openpi server (tests/servers, answering with
# the expert's recordings in out/demo) on loopback, evaluated through `autobio eval --model` with
# pi0's layout plus reset frames (so the server knows each episode), then stopped. The run is the
# `demo` suite's, so it is packed as a leaderboard bundle, verified (every episode re-enacted from
# its seed and actions) and built into the leaderboard site beside the paper's reference entry.
# Then the same server as three "checkpoints", one per training seed (`eval --checkpoint NAME
# --training-seed K`, each run K of the suite only), packed as one submission whose ± the site
# shows over training seeds, in its own column, as the paper's.
set -euo pipefail
cd "$(dirname "$0")/.."
autobio() {
  if [ -n "${AUTOBIO:-}" ]; then "$AUTOBIO" "$@"; else ${CARGO:-cargo} run --release --quiet -- "$@"; fi
}
out=out/demo
# The expert's recordings of every seed the suite plans (its three runs), for the server to answer
# with.
autobio eval --suite suites/demo.toml --out "$out/expert-suite"
log=$(mktemp)
.deps/servers/bin/python tests/servers/openpi_server.py --recordings "$out/expert-suite" >"$log" 2>&1 &
server=$!
trap 'kill $server 2>/dev/null || true; rm -f "$log"' EXIT
for _ in $(seq 100); do grep -q listening "$log" && break; sleep 0.1; done
url=$(sed -n 's/^listening on //p' "$log")
[ -n "$url" ] || { cat "$log" >&2; exit 1; }
sed -e 's/^reset_frame = false/reset_frame = true/' profiles/pi0.toml >"$out/pi0-reset.toml"
autobio eval --model "$url" --profile "$out/pi0-reset.toml" --suite suites/demo.toml --out "$out/model"
mkdir -p "$out/bundles"
autobio leaderboard submit "$out/model" --model-name "reference server (expert replay)" \
  --training "the scripted expert's recordings" --out "$out/bundles/reference-server.tar.zst"
autobio leaderboard verify "$out/bundles/reference-server.tar.zst"
for k in 0 1 2; do
  autobio eval --model "$url" --profile "$out/pi0-reset.toml" --suite suites/demo.toml \
    --checkpoint "expert-replay/seed$k" --training-seed "$k" --out "$out/seed$k"
done
autobio leaderboard submit "$out/seed0" "$out/seed1" "$out/seed2" \
  --model-name "reference server, three training seeds" \
  --training "three checkpoints replaying the expert" --out "$out/bundles/three-seeds.tar.zst"
autobio leaderboard verify "$out/bundles/three-seeds.tar.zst"
autobio leaderboard build "$out/bundles" --out "$out/site"
