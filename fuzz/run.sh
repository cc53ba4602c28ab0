#!/usr/bin/env bash
# Fuzzes parse + check + prove + lower for SECONDS (default 600), seeded with every shipped protocol
# and the faulty corpus; or, as `run.sh import_opentrons SECONDS DIR` (`import_autoprotocol`), the
# Opentrons (Autoprotocol) importer, seeded with the JSON files under DIR. The toolchain is stable; cargo-fuzz needs nightly flags, hence
# RUSTC_BOOTSTRAP. Findings land in fuzz/artifacts/; add each to tests/corpus/fuzz/ once fixed.
set -euo pipefail
cd "$(dirname "$0")"
command -v cargo-fuzz >/dev/null || cargo install cargo-fuzz --locked
if [ "${1:-}" = import_opentrons ] || [ "${1:-}" = import_autoprotocol ]; then
  target="$1"
  seconds="${2:-600}"
  mkdir -p "corpus/$target"
  if [ -n "${3:-}" ]; then cp "$3"/*.json "corpus/$target/"; fi
  exec env RUSTC_BOOTSTRAP=1 cargo fuzz run -O "$target" "corpus/$target" -- \
    -max_total_time="$seconds" -rss_limit_mb=2048 -print_final_stats=1
fi
seconds="${1:-600}"
mkdir -p corpus/parse_check_compile
cp ../protocols/*/*.toml ../tests/corpus/faulty/*.toml corpus/parse_check_compile/
RUSTC_BOOTSTRAP=1 cargo fuzz run -O parse_check_compile corpus/parse_check_compile -- \
  -dict=protocol.dict -max_total_time="$seconds" -rss_limit_mb=2048 -print_final_stats=1
