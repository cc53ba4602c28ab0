"""Why a learned policy scores what it does: three checks on a dataset and a checkpoint.

``python -m autobio.diagnose --dataset TRAIN [--policy CKPT] [--held-out HELD] [--rollouts N]``
(docs/baseline.md). Needs ``pyarrow`` (any LeRobot environment has it); the policy checks need
``lerobot`` 0.4.x.

- **alignment** (dataset only): each episode of TRAIN is re-enacted in the simulator from its
  seed (``meta/autobio.jsonl``) with the dataset's own actions, and with them one frame earlier
  and one later: if ``action[t]`` is what the expert commanded after observing frame ``t``, the
  re-enactment passes through the recorded ``observation.state`` (and
  ``observation.environment_state``) to float32's rounding, longer than either shifted one
  (``aligned``), and ends in success. (float32 actions leave a gap of about 1e-8 that a grasp's
  contacts can grow past 1e-3 late in an episode; a shifted, scaled or reordered action parts
  at once.) ``--shift K`` replays ``action[t + K]`` at frame ``t`` to show the check failing.
- **open-loop** (``--policy`` and ``--held-out``): on each frame of demonstrations the policy
  never saw, the first action the policy predicts from a fresh start, against the expert's
  ``action[t]``; errors per action dimension in units of the training actions' standard
  deviation, beside the error of always answering the training mean (a policy that has learned
  nothing scores about that).
- **drift** (``--policy`` and ``--rollouts``): the policy run closed-loop on unseen seeds; at
  each step the distance from its (environment and robot) state to the nearest training frame,
  in units of each dimension's standard deviation; the first step where it exceeds what held-out
  expert frames reach (their 99th percentile) for 5 steps running is where the rollout left the
  demonstrations' state distribution, with the dimensions that moved most; and how far through
  a demonstration its nearest training frame ever got (a rollout that stalls never leaves the
  distribution but stops advancing).

It reports and does not judge: the numbers and where they come from, as text or ``--json``.
"""

import argparse
import glob
import json
import os
import sys
from dataclasses import dataclass

import numpy as np

from . import env as _env

STATE = "observation.state"
ENVIRONMENT = "observation.environment_state"
ACTION = "action"
# A standard deviation below this (a dimension the demonstrations never move) counts as this,
# so a rollout moving it reads as far out, not as infinitely far.
STD_FLOOR = 1e-3
# Steps a rollout stays beyond the threshold before it counts as having left.
PERSIST = 5


@dataclass
class Episode:
    index: int
    task: str
    seed: int
    state: np.ndarray
    environment_state: np.ndarray | None
    action: np.ndarray


@dataclass
class Dataset:
    root: str
    episodes: list
    info: dict

    def names(self, key):
        names = self.info["features"].get(key, {}).get("names")
        return list(names) if names else []

    def frames(self, key):
        attr = {STATE: "state", ENVIRONMENT: "environment_state", ACTION: "action"}[key]
        return np.concatenate([getattr(e, attr) for e in self.episodes])


def read_dataset(root):
    """A LeRobot dataset that autobio wrote (v2.1 or v3.0): every episode's state, environment
    state (where recorded) and action columns, with its task and seed."""
    import pyarrow.parquet as pq

    with open(os.path.join(root, "meta/info.json")) as f:
        info = json.load(f)
    seeds = {}
    with open(os.path.join(root, "meta/autobio.jsonl")) as f:
        for line in f:
            if line.strip():
                r = json.loads(line)
                seeds[r["episode_index"]] = (r["task_id"], int(r["seed"]))
    files = sorted(glob.glob(os.path.join(root, "data/**/*.parquet"), recursive=True))
    if not files:
        raise FileNotFoundError(f"{root}: no parquet files under data/")
    wanted = [c for c in ("episode_index", "frame_index", STATE, ENVIRONMENT, ACTION)]
    columns = {}
    for path in files:
        table = pq.read_table(path)
        for c in wanted:
            if c in table.column_names:
                columns.setdefault(c, []).extend(table.column(c).to_pylist())
    order = np.lexsort((np.asarray(columns["frame_index"]), np.asarray(columns["episode_index"])))
    ep = np.asarray(columns["episode_index"])[order]
    arrays = {
        c: np.asarray([columns[c][i] for i in order], dtype=np.float64)
        for c in (STATE, ENVIRONMENT, ACTION)
        if c in columns
    }
    episodes = []
    for index in np.unique(ep):
        rows = ep == index
        task, seed = seeds[int(index)]
        episodes.append(
            Episode(
                int(index),
                task,
                seed,
                arrays[STATE][rows],
                arrays[ENVIRONMENT][rows] if ENVIRONMENT in arrays else None,
                arrays[ACTION][rows],
            )
        )
    return Dataset(root, episodes, info)


def _replay(env, e, shift):
    """Re-enacts episode ``e`` with ``action[t + shift]`` at frame ``t`` (clamped to the
    episode): the largest gap to the recorded states, the frames tracked (those before the gap
    first exceeds 1e-3) and whether the re-enactment succeeded."""
    obs, _ = env.reset(seed=e.seed)
    gaps, success = [], False
    last = len(e.action) - 1
    for t in range(len(e.action)):
        gap = float(np.max(np.abs(obs["agent_pos"] - e.state[t])))
        if e.environment_state is not None:
            gap = max(gap, float(np.max(np.abs(obs["environment_state"] - e.environment_state[t]))))
        gaps.append(gap)
        action = np.clip(e.action[min(max(t + shift, 0), last)], env.action_space.low, env.action_space.high)
        obs, _, terminated, truncated, info = env.step(action)
        success = success or info["is_success"]
        if terminated or truncated:
            break
    beyond = [t for t, g in enumerate(gaps) if g > 1e-3]
    return max(gaps), (beyond[0] if beyond else len(gaps)), success


def alignment(dataset, episodes=None, shift=0):
    """Re-enacts ``episodes`` (all by default) of ``dataset`` with its own actions
    (``action[t + shift]`` at frame ``t``), and with them one frame earlier and later: per
    episode the largest gap between the re-enacted and recorded states, the first frame where it
    exceeds 1e-3, whether the re-enactment succeeded, and whether it tracks the recording longer
    than both neighbours (``aligned``: ``action[t]`` is what was commanded after observing frame
    ``t``). Actions stored as float32 re-enact a contact-rich episode to float32's rounding until
    a contact amplifies it (a grasp); a misaligned one parts at once."""
    chosen = dataset.episodes if episodes is None else dataset.episodes[:episodes]
    reports = []
    env = None
    for e in chosen:
        obs_type = "environment_state_agent_pos" if e.environment_state is not None else "pixels_agent_pos"
        if env is None or env.task_id != e.task:
            env = _env.make(e.task, image_size=8, obs_type=obs_type)
        max_gap, tracked, success = _replay(env, e, shift)
        before = _replay(env, e, shift - 1)[1]
        after = _replay(env, e, shift + 1)[1]
        reports.append(
            {
                "episode": e.index,
                "seed": e.seed,
                "frames": len(e.action),
                "max_gap": max_gap,
                "first_divergent_frame": None if tracked == len(e.action) else tracked,
                "success": bool(success),
                "frames_tracked": {"-1": before, "0": tracked, "+1": after},
                "aligned": tracked > max(before, after),
            }
        )
    return reports


def _standardiser(frames):
    mean = frames.mean(axis=0)
    std = np.maximum(frames.std(axis=0), STD_FLOOR)
    return mean, std


def open_loop(runner, train, held_out):
    """The policy's first predicted action on every frame of ``held_out``, against the expert's,
    in units of ``train``'s action standard deviation per dimension."""
    mean, std = _standardiser(train.frames(ACTION))
    errors = []
    for e in held_out.episodes:
        obs = {"agent_pos": e.state}
        if e.environment_state is not None:
            obs["environment_state"] = e.environment_state
        errors.append(np.abs(runner.first_actions(obs) - e.action) / std)
    errors = np.concatenate(errors)
    expert = held_out.frames(ACTION)
    mean_errors = np.abs(expert - mean) / std
    names = train.names(ACTION) or [str(i) for i in range(errors.shape[1])]
    per_dim = errors.mean(axis=0)
    worst = np.argsort(-per_dim)[:5]
    return {
        "frames": int(errors.shape[0]),
        "error_std": float(errors.mean()),
        "mean_action_error_std": float(mean_errors.mean()),
        "per_dimension": {names[i]: float(per_dim[i]) for i in range(len(names))},
        "worst": [names[i] for i in worst],
    }


def _features(episode_or_obs):
    if isinstance(episode_or_obs, Episode):
        parts = [episode_or_obs.state]
        if episode_or_obs.environment_state is not None:
            parts.insert(0, episode_or_obs.environment_state)
        return np.concatenate(parts, axis=1)
    parts = [episode_or_obs["agent_pos"]]
    if "environment_state" in episode_or_obs:
        parts.insert(0, episode_or_obs["environment_state"])
    return np.concatenate(parts)


def _nearest(points, reference, chunk=256):
    """Per point: the distance to its nearest reference row and that row's index."""
    ref_sq = np.sum(reference * reference, axis=1)
    dist, idx = [], []
    for i in range(0, len(points), chunk):
        p = points[i : i + chunk]
        d = ref_sq[None, :] - 2.0 * p @ reference.T + np.sum(p * p, axis=1)[:, None]
        j = np.argmin(d, axis=1)
        idx.append(j)
        dist.append(np.sqrt(np.maximum(d[np.arange(len(p)), j], 0.0)))
    return np.concatenate(dist), np.concatenate(idx)


def drift(runner, train, held_out, task, seeds, threshold_quantile=0.99):
    """Closed-loop rollouts of the policy on ``seeds``: per rollout whether it succeeded, its
    length, and the first step where its state left the demonstrations' distribution."""
    reference = np.concatenate([_features(e) for e in train.episodes])
    # Each training frame's phase: how far through its demonstration it is (0 to 1).
    phase = np.concatenate([np.linspace(0.0, 1.0, len(e.action)) for e in train.episodes])
    mean, std = _standardiser(reference)
    reference = (reference - mean) / std
    held = np.concatenate([_features(e) for e in held_out.episodes])
    held_dist, _ = _nearest((held - mean) / std, reference)
    threshold = float(np.quantile(held_dist, threshold_quantile))
    names = train.names(ENVIRONMENT) + train.names(STATE)
    obs_type = "environment_state_agent_pos" if runner.reads_environment_state else "pixels_agent_pos"
    # Clipped to the actuators' ranges as lerobot-eval's env type does (a checkpoint without
    # saved action statistics is not clipped by its Runner).
    env = _env.make(task, image_size=8 if obs_type.startswith("environment") else 224,
                    obs_type=obs_type, clip_actions=True)
    rollouts = []
    for seed in seeds:
        obs, info = env.reset(seed=seed)
        runner.reset()
        visited = [_features(obs)]
        success = False
        while True:
            obs, _, terminated, truncated, info = env.step(runner.act(obs, info["instruction"]))
            visited.append(_features(obs))
            success = success or info["is_success"]
            if terminated or truncated:
                break
        z = (np.asarray(visited) - mean) / std
        dist, nearest = _nearest(z, reference)
        beyond = dist > threshold
        left = None
        for t in range(len(beyond) - PERSIST + 1):
            if beyond[t : t + PERSIST].all():
                left = t
                break
        moved = []
        if left is not None:
            gap = np.abs(z[left] - reference[nearest[left]])
            moved = [names[i] if i < len(names) else str(i) for i in np.argsort(-gap)[:3]]
        rollouts.append(
            {
                "seed": seed,
                "success": bool(success),
                "steps": len(visited) - 1,
                "left_distribution_at": left,
                "moved_most": moved,
                "max_distance": float(dist.max()),
                # How far through a demonstration the nearest training frame ever was, and the
                # step it was first reached: a rollout that stalls stays in the distribution
                # but stops advancing.
                "furthest_phase": float(phase[nearest].max()),
                "furthest_phase_at": int(np.argmax(phase[nearest])),
            }
        )
    return {"threshold": threshold, "rollouts": rollouts}


def _print_report(report, out):
    if "alignment" in report:
        a = report["alignment"]
        ok = sum(1 for r in a if r["first_divergent_frame"] is None and r["success"])
        aligned = sum(1 for r in a if r["aligned"])
        print(f"alignment: {aligned}/{len(a)} episodes track their recording longest with "
              f"action[t] at frame t; {ok}/{len(a)} re-enacted exactly and succeeded "
              f"(shift {report['shift']})", file=out)
        for r in a:
            k = r["frames_tracked"]
            print(f"  episode {r['episode']} seed {r['seed']}: {r['frames']} frames, max gap "
                  f"{r['max_gap']:.2e}, first divergent frame {r['first_divergent_frame']}, "
                  f"success {r['success']}; frames tracked one earlier / as is / one later: "
                  f"{k['-1']} / {k['0']} / {k['+1']}", file=out)
    if "open_loop" in report and "skipped" in report["open_loop"]:
        print(f"open-loop: skipped ({report['open_loop']['skipped']})", file=out)
    elif "open_loop" in report:
        o = report["open_loop"]
        print(f"open-loop: {o['frames']} held-out frames, mean |error| {o['error_std']:.3f} std "
              f"(the training mean scores {o['mean_action_error_std']:.3f}); worst: "
              + ", ".join(f"{n} {o['per_dimension'][n]:.3f}" for n in o["worst"]), file=out)
    if "drift" in report:
        d = report["drift"]
        print(f"drift: threshold {d['threshold']:.3f} (99th percentile of held-out expert frames)", file=out)
        for r in d["rollouts"]:
            where = ("never left" if r["left_distribution_at"] is None else
                     f"left at step {r['left_distribution_at']} ({', '.join(r['moved_most'])})")
            print(f"  seed {r['seed']}: success {r['success']}, {r['steps']} steps, {where}; "
                  f"got {100 * r['furthest_phase']:.0f}% through a demonstration (step "
                  f"{r['furthest_phase_at']})", file=out)


def main(argv=None):
    p = argparse.ArgumentParser(prog="python -m autobio.diagnose", description=__doc__.split("\n\n")[0])
    p.add_argument("--dataset", required=True, help="the training dataset (autobio demo --format lerobot-*)")
    p.add_argument("--policy", help="a LeRobot checkpoint (.../pretrained_model) for open-loop and drift")
    p.add_argument("--held-out", help="demonstrations the policy never saw (open-loop; drift's threshold)")
    p.add_argument("--episodes", type=int, help="alignment: re-enact only the first N episodes")
    p.add_argument("--shift", type=int, default=0, help="alignment: replay action[t + K] at frame t")
    p.add_argument("--no-alignment", action="store_true", help="skip the alignment check")
    p.add_argument("--rollouts", type=int, default=0, help="drift: closed-loop rollouts of the policy")
    p.add_argument("--seed", type=int, default=1000, help="drift: the first rollout's seed")
    p.add_argument("--device", default="cpu")
    p.add_argument("--json", help="also write the report as JSON here")
    args = p.parse_args(argv)
    if args.policy and not args.held_out:
        p.error("--policy needs --held-out (demonstrations the policy never saw)")
    train = read_dataset(args.dataset)
    report = {"dataset": args.dataset, "shift": args.shift}
    if not args.no_alignment:
        report["alignment"] = alignment(train, args.episodes, args.shift)
    if args.policy:
        from .lerobot import load_policy

        held = read_dataset(args.held_out)
        runner = load_policy(args.policy, device=args.device)
        report["policy"] = args.policy
        if any(k.startswith("observation.images.") for k in runner.input_features):
            # The frames are in the held-out videos; decoding them is LeRobot's dataset's job.
            report["open_loop"] = {"skipped": "the policy reads cameras: open-loop error is "
                                   "measured on state policies only"}
        else:
            report["open_loop"] = open_loop(runner, train, held)
        if args.rollouts:
            task = train.episodes[0].task
            seeds = list(range(args.seed, args.seed + args.rollouts))
            report["drift"] = drift(runner, train, held, task, seeds)
    _print_report(report, sys.stdout)
    if args.json:
        with open(args.json, "w") as f:
            json.dump(report, f, indent=2)
    return 0


if __name__ == "__main__":
    sys.exit(main())
