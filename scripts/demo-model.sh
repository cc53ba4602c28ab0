#!/usr/bin/env bash
# The model-server part of `make demo`: the reference openpi server (tests/servers, answering with
# the expert's recordings in out/demo) on loopback, evaluated through `autobio eval --model` with
# pi0's layout plus reset frames (so the server knows each episode), then stopped. The run is the
# `demo` suite's, so it is packed as a leaderboard bundle, verified (every episode re-enacted from
# its seed and actions) and built into the leaderboard site beside the paper's reference entry.
set -euo pipefail
cd "$(dirname "$0")/.."
autobio() {
  if [ -n "${AUTOBIO:-}" ]; then "$AUTOBIO" "$@"; else ${CARGO:-cargo} run --release --quiet -- "$@"; fi
}
out=out/demo
log=$(mktemp)
.deps/servers/bin/python tests/servers/openpi_server.py --recordings "$out" >"$log" 2>&1 &
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
autobio leaderboard build "$out/bundles" --out "$out/site"
