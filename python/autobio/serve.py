"""Serve a LeRobot checkpoint to ``autobio eval --model`` over openpi's websocket protocol.

    python -m autobio.serve --policy out/train/checkpoints/last/pretrained_model --port 8000
    autobio eval --protocol P.toml --model ws://127.0.0.1:8000 --wire openpi --profile lerobot-state

``--policy TASK_ID=CHECKPOINT`` (repeated) serves one checkpoint per task, chosen by the task id
each episode's reset frame names, so a suite of tasks with a policy each runs as one model.

What it speaks is openpi's ``WebsocketPolicyServer`` protocol: a metadata frame on connect, then
strictly one reply per observation, each frame msgpack with numpy arrays in openpi's
msgpack-numpy form; an error is a text frame holding the traceback, then close code 1011. A
``{"reset": true}`` frame (the profile's ``reset_frame``) starts an episode: the policy's action
queue is cleared, no reply.

Observations are read by LeRobot's own feature names, which the built-in profiles
``lerobot-state`` and ``lerobot-vision`` send: ``observation.state``,
``observation.environment_state``, ``observation.images.<camera>`` (uint8 HWC) and ``task``
(the instruction). Each reply is ``{"actions": (1, A) float64}``: the policy's ``select_action``
with its own queue and its own pre- and post-processors, exactly as ``lerobot-eval`` steps it
(``autobio.lerobot.Runner``), so the profile runs one action per query. Each action is clipped to
the range of the demonstrations' actions (``--no-clip``: sent as the policy made it); autobio
itself never clamps, and refuses an action outside an actuator's range as the policy's error.

Prints ``listening on ws://HOST:PORT`` once ready (``--port 0`` picks a free one).
"""

import argparse
import asyncio
import contextlib
import copy
import json
import os
import sys
import traceback

import msgpack
import numpy as np
from websockets.asyncio.server import serve
from websockets.exceptions import ConnectionClosed

from . import __version__


def _pack_default(obj):
    """openpi's msgpack-numpy: arrays as ``__ndarray__`` maps, numpy scalars as ``__npgeneric__``."""
    if isinstance(obj, np.ndarray):
        if obj.dtype.kind not in "biufc":
            raise TypeError(f"cannot send an array of dtype {obj.dtype}")
        return {
            b"__ndarray__": True,
            b"data": obj.tobytes(),
            b"dtype": obj.dtype.str,
            b"shape": obj.shape,
        }
    if isinstance(obj, np.generic):
        return {b"__npgeneric__": True, b"data": obj.item(), b"dtype": obj.dtype.str}
    return obj


def _unpack_hook(obj):
    if b"__ndarray__" in obj:
        return np.ndarray(
            buffer=obj[b"data"], dtype=np.dtype(obj[b"dtype"]), shape=obj[b"shape"]
        )
    if b"__npgeneric__" in obj:
        return np.dtype(obj[b"dtype"]).type(obj[b"data"])
    return obj


def pack(value):
    return msgpack.packb(value, default=_pack_default, use_bin_type=True)


def unpack(data):
    return msgpack.unpackb(data, object_hook=_unpack_hook, raw=False, strict_map_key=False)


def _key(k):
    return k.decode() if isinstance(k, bytes) else k


def observation_from_wire(frame):
    """A wire observation (LeRobot's feature names) as a gym-style observation and the task."""
    frame = {_key(k): v for k, v in frame.items()}
    obs = {}
    pixels = {
        k[len("observation.images."):]: np.asarray(v, dtype=np.uint8)
        for k, v in frame.items()
        if k.startswith("observation.images.") and v is not None
    }
    if pixels:
        obs["pixels"] = pixels
    if frame.get("observation.environment_state") is not None:
        obs["environment_state"] = np.asarray(frame["observation.environment_state"])
    if frame.get("observation.state") is not None:
        obs["agent_pos"] = np.asarray(frame["observation.state"])
    task = frame.get("task")
    return obs, task.decode() if isinstance(task, bytes) else task


def check_inputs(runner, obs):
    """Raises ``ValueError`` naming each input feature the policy needs that the observation
    lacks or gives in another shape."""
    have = {}
    for camera, img in obs.get("pixels", {}).items():
        have[f"observation.images.{camera}"] = tuple(np.transpose(img, (2, 0, 1)).shape)
    if "environment_state" in obs:
        have["observation.environment_state"] = tuple(obs["environment_state"].shape)
    if "agent_pos" in obs:
        have["observation.state"] = tuple(obs["agent_pos"].shape)
    wrong = []
    for name, shape in runner.input_features.items():
        if name not in have:
            wrong.append(f"{name} is missing (the profile sends {sorted(have)})")
        elif have[name] != shape:
            wrong.append(f"{name} has shape {have[name]}, the policy was trained on {shape}")
    if wrong:
        raise ValueError("; ".join(wrong))


def describe(runner):
    """What the metadata frame says of one checkpoint: its type, input features and how it was
    trained (from the ``train_config.json`` ``lerobot-train`` saved beside it)."""
    out = {
        "policy_type": runner.config.type,
        "checkpoint": runner.path,
        "input_features": {k: list(v) for k, v in runner.input_features.items()},
        "observation_mode": "state" if runner.reads_environment_state else "vision",
        "actions_clipped_to_demonstrations": bool(runner.clip),
    }
    try:
        with open(os.path.join(runner.path, "train_config.json")) as f:
            train = json.load(f)
        out["training"] = {
            "steps": train.get("steps"),
            "batch_size": train.get("batch_size"),
            "seed": train.get("seed"),
            "dataset": (train.get("dataset") or {}).get("repo_id"),
        }
    except (OSError, ValueError):
        pass
    return out


def metadata(runners):
    modes = {describe(r)["observation_mode"] for r in runners.values()}
    return {
        "server": "autobio.serve",
        "autobio_version": __version__,
        "observation_mode": "state" if "state" in modes else "vision",
        "policies": {task or "*": describe(r) for task, r in sorted(runners.items(), key=str)},
    }


class Policies:
    """The checkpoints one connection serves: its own copy of each (a policy's action queue is
    per episode), the one for the running episode's task chosen at each reset frame."""

    def __init__(self, loaded, first):
        self.loaded = loaded
        # Never the loaded objects themselves: a copy is taken at a connection's first reset, and
        # another connection may be running its policy meanwhile (eval --workers N).
        self.mine = {}
        self.runner = None

    def select(self, task_id):
        key = task_id if task_id in self.loaded else None
        if key not in self.loaded:
            raise ValueError(
                f"no policy for task {task_id!r}; this server has {sorted(self.loaded)}"
            )
        if key not in self.mine:
            self.mine[key] = copy.deepcopy(self.loaded[key])
        self.runner = self.mine[key]
        self.runner.reset()
        return self.runner


def _task_id(frame):
    task = frame.get("task", frame.get(b"task"))
    if isinstance(task, dict):
        task = {_key(k): v for k, v in task.items()}
        tid = task.get("id")
        return tid.decode() if isinstance(tid, bytes) else tid
    return None


async def _connection(ws, policies, loaded, args):
    await ws.send(pack(metadata(loaded)))
    runner = policies.select(None) if None in loaded else None
    checked = False
    while True:
        try:
            data = await ws.recv()
        except ConnectionClosed:
            return
        try:
            frame = unpack(data)
            if not isinstance(frame, dict):
                raise ValueError(f"an observation must be a map, not {type(frame).__name__}")
            if frame.get("reset") or frame.get(b"reset"):
                runner = policies.select(_task_id(frame))
                checked = False
                continue
            if runner is None:
                raise ValueError(
                    "this server holds one policy per task: send a reset frame naming the task "
                    "first (the profile's reset_frame = true)"
                )
            obs, task = observation_from_wire(frame)
            if not checked:
                check_inputs(runner, obs)
                checked = True
            action = await asyncio.to_thread(runner.act, obs, task)
            await ws.send(pack({"actions": action[None, :]}))
        except ConnectionClosed:
            return
        except Exception:
            await ws.send(traceback.format_exc())
            await ws.close(code=1011, reason="the policy failed")
            return


async def _main(args):
    from .lerobot import load_policy

    loaded = {}
    # `listening on` is the first line on stdout: what LeRobot prints while loading goes to stderr.
    with contextlib.redirect_stdout(sys.stderr):
        for spec in args.policy:
            task, sep, path = spec.rpartition("=")
            loaded[task if sep else None] = load_policy(path, device=args.device, clip=args.clip)
    connections = [0]

    async def handler(ws):
        # A policy's action queue is per episode: each connection (an eval worker) gets its own
        # copies of the loaded policies.
        connections[0] += 1
        await _connection(ws, Policies(loaded, connections[0] == 1), loaded, args)

    async with serve(handler, args.host, args.port, max_size=None, compression=None) as server:
        port = server.sockets[0].getsockname()[1]
        print(f"listening on ws://{args.host}:{port}", flush=True)
        await server.serve_forever()


def main(argv=None):
    p = argparse.ArgumentParser(prog="python -m autobio.serve", description=__doc__.split("\n")[0])
    p.add_argument(
        "--policy",
        required=True,
        action="append",
        help="a LeRobot checkpoint's pretrained_model folder, or TASK_ID=FOLDER (repeated: a "
        "policy per task)",
    )
    p.add_argument("--host", default="127.0.0.1")
    p.add_argument("--port", type=int, default=8000, help="0 picks a free port")
    p.add_argument("--device", default="cpu")
    p.add_argument(
        "--no-clip",
        dest="clip",
        action="store_false",
        help="send actions as the policy makes them (default: clipped to the demonstrations' range)",
    )
    args = p.parse_args(argv)
    try:
        asyncio.run(_main(args))
    except KeyboardInterrupt:
        return 0
    return 0


if __name__ == "__main__":
    sys.exit(main())
