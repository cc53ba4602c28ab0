#!/usr/bin/env bash
# The learned baseline (`make baseline`; docs/baseline.md): for each task of suites/baseline.toml,
# DEMOS expert demonstrations (seeds 0..DEMOS-1) as a LeRobot v3.0 dataset, a policy trained on
# them with LeRobot's own `lerobot-train` (ACT by default, on the CPU), then every saved
# checkpoint evaluated on seeds no demonstration used (the learning curve), and the last served
# (`python -m autobio.serve`, one checkpoint per task) to `autobio eval --suite
# suites/baseline.toml --model`, packed as a leaderboard bundle, verified (every episode
# re-enacted) and built into a site beside the paper's rows.
#
# OBS=state (default) trains on the task's environment state and the robot state, no camera:
# what 2 CPU cores train in a working day. OBS=vision trains on the cameras (224x224) and the
# robot state, the same recipe for a machine with a GPU (DEVICE=cuda): the backbone starts from
# scratch here (no ImageNet weights offline), or from a checkpoint the user's POLICY_ARGS name.
#
# Every stage resumes: a dataset, a training or an evaluation already finished is not redone.
set -euo pipefail
cd "$(dirname "$0")/.."
OUT=${OUT:-out/baseline}
DEMOS=${DEMOS:-100}
STEPS=${STEPS:-6000}
# Checkpoints saved (and evaluated for the learning curve) every STEPS/CURVE steps.
CURVE=${CURVE:-3}
BATCH=${BATCH:-32}
OBS=${OBS:-state}
DEVICE=${DEVICE:-cpu}
POLICY=${POLICY:-act}
# Episodes per task for each checkpoint of the learning curve (seeds 1000 and up).
CURVE_EPISODES=${CURVE_EPISODES:-10}
SUITE=${SUITE:-suites/baseline.toml}
# ACT sized for a state vector: a small transformer, no VAE, chunks of 20 actions of which 10 run
# before the policy looks again; learning rate 1e-4 (from scratch). On cameras: ACT's own sizes
# (ResNet-18, width 512), the same chunks, the backbone from scratch (torchvision's ImageNet
# weights need a download: BACKBONE=ResNet18_Weights.IMAGENET1K_V1 where one is possible).
if [ "$OBS" = state ]; then
  POLICY_ARGS=${POLICY_ARGS:---policy.dim_model=256 --policy.n_heads=4 --policy.dim_feedforward=1024 --policy.n_encoder_layers=2 --policy.n_decoder_layers=1 --policy.chunk_size=20 --policy.n_action_steps=10 --policy.use_vae=false --policy.optimizer_lr=1e-4}
else
  POLICY_ARGS=${POLICY_ARGS:---policy.pretrained_backbone_weights=${BACKBONE:-null} --policy.chunk_size=20 --policy.n_action_steps=10 --policy.use_vae=false --policy.optimizer_lr=1e-4}
fi
LR=.deps/lerobot-env/bin/python
autobio() {
  if [ -n "${AUTOBIO:-}" ]; then "$AUTOBIO" "$@"; else ${CARGO:-cargo} run --release --quiet -- "$@"; fi
}
[ -x "$LR" ] || { echo "baseline: run make setup first (LeRobot's environment)" >&2; exit 1; }
mkdir -p "$OUT"
tasks=$(sed -n 's|^ *"\.\./\(protocols/.*\.toml\)",*|\1|p' "$SUITE")
id_of() { autobio compile "$1" | sed -n 's/^  "id": "\(.*\)",$/\1/p'; }
every=$((STEPS / CURVE))
[ "$every" -ge 1 ] || { echo "baseline: CURVE ($CURVE) must not exceed STEPS ($STEPS)" >&2; exit 1; }
serve_args=()
for protocol in $tasks; do
  id=$(id_of "$protocol")
  data="$OUT/data/$id"
  done_demos=$(grep -c . "$data/meta/autobio.jsonl" 2>/dev/null) || true
  if [ ! -e "$data/meta/info.json" ] || [ "${done_demos:-0}" -lt "$DEMOS" ]; then
    autobio demo --protocol "$protocol" --episodes "$DEMOS" --seed 0 --format lerobot-v30 \
      --observation "$OBS" --out "$data" --resume
  fi
  train="$OUT/train/$id"
  if [ ! -e "$train/checkpoints/last/pretrained_model/model.safetensors" ]; then
    rm -rf "$train"
    start=$(date +%s)
    # Every feature normalised by its dataset statistics, the environment state (ENV) included
    # (ACT's default mapping leaves it raw).
    "$LR" -m lerobot.scripts.lerobot_train --dataset.repo_id="autobio/$id" --dataset.root="$data" \
      --policy.type="$POLICY" --policy.device="$DEVICE" --policy.push_to_hub=false \
      --policy.normalization_mapping='{"VISUAL": "MEAN_STD", "STATE": "MEAN_STD", "ENV": "MEAN_STD", "ACTION": "MEAN_STD"}' \
      $POLICY_ARGS --output_dir="$train" --steps="$STEPS" --batch_size="$BATCH" \
      --save_freq="$every" --eval_freq=0 --log_freq=200 --num_workers=0 --seed=0 \
      --wandb.enable=false
    echo "{\"task\": \"$id\", \"demos\": $DEMOS, \"steps\": $STEPS, \"batch_size\": $BATCH, \"observation\": \"$OBS\", \"policy\": \"$POLICY\", \"device\": \"$DEVICE\", \"wall_s\": $(( $(date +%s) - start ))}" >"$train/autobio-training.json"
  fi
  serve_args+=(--policy "$id=$train/checkpoints/last/pretrained_model")
done
# The model profile of the evaluations: what the policy reads, as the wire sends it.
PROFILE=${PROFILE:-lerobot-$OBS}

# Serves the checkpoints of step $1 (or `last`), one per task; sets $url and $server.
serve() {
  local args=() log
  for protocol in $tasks; do
    local id; id=$(id_of "$protocol")
    args+=(--policy "$id=$OUT/train/$id/checkpoints/$1/pretrained_model")
  done
  log=$(mktemp)
  "$LR" -m autobio.serve "${args[@]}" --port 0 >"$log" 2>&1 &
  server=$!
  for _ in $(seq 600); do grep -q listening "$log" && break; kill -0 $server 2>/dev/null || break; sleep 0.2; done
  url=$(sed -n 's/^listening on //p' "$log")
  [ -n "$url" ] || { cat "$log" >&2; exit 1; }
}
trap 'kill ${server:-} 2>/dev/null || true' EXIT

# The learning curve: each saved checkpoint on CURVE_EPISODES unseen seeds per task.
for k in $(seq 1 "$CURVE"); do
  step=$(printf '%06d' $((k * every)))
  curve="$OUT/curve/$step"
  [ -e "$curve/done" ] && continue
  serve "$step"
  rm -rf "$curve"
  for protocol in $tasks; do
    autobio eval --protocol "$protocol" --model "$url" --wire openpi --profile "$PROFILE" \
      --episodes "$CURVE_EPISODES" --seed 1000 --out "$curve"
  done
  kill "$server" 2>/dev/null || true; wait "$server" 2>/dev/null || true
  touch "$curve/done"
done

# The last checkpoints on the suite: packed, verified and built into the site.
if [ ! -e "$OUT/suite/done" ]; then
  serve last
  rm -rf "$OUT/suite"
  autobio eval --suite "$SUITE" --model "$url" --wire openpi --profile "$PROFILE" --out "$OUT/suite"
  kill "$server" 2>/dev/null || true; wait "$server" 2>/dev/null || true
  touch "$OUT/suite/done"
fi
mkdir -p "$OUT/bundles"
autobio leaderboard submit "$OUT/suite" --model-name "$(echo "$POLICY" | tr '[:lower:]' '[:upper:]') ($OBS), autobio baseline" \
  --training "$DEMOS expert demos per task (seeds 0-$((DEMOS - 1))), $STEPS steps, batch $BATCH, $OBS observation, lerobot-train on $DEVICE" \
  --out "$OUT/bundles/$POLICY-$OBS.tar.zst"
autobio leaderboard verify "$OUT/bundles/$POLICY-$OBS.tar.zst"
autobio leaderboard build "$OUT/bundles" --out "$OUT/site"

# The diagnosis (python -m autobio.diagnose): the training data re-enacted from its seeds with
# its own actions (alignment), the last checkpoint's open-loop error on HELD_OUT demonstrations
# it never saw (seeds 5000 and up), and where DRIFT closed-loop rollouts leave the
# demonstrations' state distribution.
HELD_OUT=${HELD_OUT:-10}
DRIFT=${DRIFT:-5}
for protocol in $tasks; do
  id=$(id_of "$protocol")
  [ -e "$OUT/diagnosis/$id.json" ] && continue
  mkdir -p "$OUT/diagnosis"
  held="$OUT/held-out/$id"
  rm -rf "$held"
  autobio demo --protocol "$protocol" --episodes "$HELD_OUT" --seed 5000 --format lerobot-v30 \
    --observation "$OBS" --out "$held"
  "$LR" -m autobio.diagnose --dataset "$OUT/data/$id" --episodes "$HELD_OUT" \
    --policy "$OUT/train/$id/checkpoints/last/pretrained_model" --held-out "$held" \
    --rollouts "$DRIFT" --seed 1000 --json "$OUT/diagnosis/$id.json" | tee "$OUT/diagnosis/$id.txt"
done
# The figures in one file: success per task with Wilson intervals, the learning curve, the
# training cost and the diagnosis's headline per task.
"$LR" - "$OUT" $tasks <<'PY' >"$OUT/summary.md"
import glob, json, os, sys
out, protocols = sys.argv[1], sys.argv[2:]
def results(folder):
    rows = {}
    for f in sorted(glob.glob(os.path.join(folder, "*.results.json"))):
        r = json.load(open(f))
        rows[r["task_id"]] = r["summary"]
    return rows
suite = results(os.path.join(out, "suite"))
print("| task | success (unseen seeds) | Wilson 95% | training wall time |")
print("|---|---|---|---|")
for task, s in suite.items():
    t = json.load(open(os.path.join(out, "train", task, "autobio-training.json")))
    lo, hi = s["wilson_95"]
    print(f"| {task} | {s['successes']}/{s['episodes']} ({100 * s['success_rate']:.0f}%) "
          f"| [{100 * lo:.0f}, {100 * hi:.0f}] | {t['wall_s'] / 60:.1f} min |")
print()
curve = {os.path.basename(d): results(d) for d in sorted(glob.glob(os.path.join(out, "curve", "*")))}
print("| training steps | " + " | ".join(suite) + " |")
print("|---" * (len(suite) + 1) + "|")
for step, rows in curve.items():
    cells = [f"{rows[t]['successes']}/{rows[t]['episodes']}" if t in rows else "-" for t in suite]
    print(f"| {int(step)} | " + " | ".join(cells) + " |")
print()
for task in suite:
    f = os.path.join(out, "diagnosis", task + ".json")
    if not os.path.exists(f):
        continue
    d = json.load(open(f))
    a = d.get("alignment", [])
    exact = sum(1 for e in a if e["first_divergent_frame"] is None and e["success"])
    aligned = sum(1 for e in a if e.get("aligned"))
    o = d.get("open_loop", {})
    line = (f"- {task}: alignment: {aligned}/{len(a)} aligned (action[t] after frame t), "
            f"{exact}/{len(a)} re-enacted exactly")
    if "error_std" in o:
        line += (f"; open-loop error {o['error_std']:.3f} std (the mean action: "
                 f"{o['mean_action_error_std']:.3f}), worst {', '.join(o['worst'][:3])}")
    for r in d.get("drift", {}).get("rollouts", []):
        left = r["left_distribution_at"]
        line += (f"; seed {r['seed']} {'won' if r['success'] else 'lost'}, "
                 + ("never left" if left is None else f"left at step {left} ({', '.join(r['moved_most'][:2])})")
                 + f", {100 * r['furthest_phase']:.0f}% through")
    print(line)
PY
cat "$OUT/summary.md"
echo "baseline: site in $OUT/site/index.html; figures in $OUT/summary.md"
