#!/usr/bin/env bash
# Joins the shards deploy/run-shard.sh wrote under OUT_ROOT into OUT_ROOT/merged, once every
# shard has finished (`autobio results merge` refuses missing, doubled or mismatched shards).
#
#   deploy/merge.sh OUT_ROOT SHARDS
set -euo pipefail
if [ $# -ne 2 ]; then
  echo "usage: $0 OUT_ROOT SHARDS" >&2
  exit 2
fi
out_root=$1
count=$2
shards=()
for ((i = 0; i < count; i++)); do
  shards+=("$out_root/shard-$i-of-$count")
done
exec "${AUTOBIO:-autobio}" results merge "${shards[@]}" --out "$out_root/merged"
