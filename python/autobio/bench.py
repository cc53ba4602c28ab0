"""Throughput of the Python package, for ``autobio bench --only python``: control steps per second
of one task from Python, through the native core alone and through the gymnasium environment
(observations as numpy arrays, info dicts), and of the vector environment with N episodes on
threads. Every step holds the robots at their targets (``--policy hold``'s action), so the
physics is the same as in the Rust harness's figure it is compared with.

``python -m autobio.bench --task ID --steps N --image-size WxH --num-envs 1,2,4`` prints one
JSON object per line: ``{"mode": ..., "num_envs": ..., "steps": ..., "seconds": ...,
"steps_per_s": ...}``.
"""

import argparse
import json
import time

import numpy as np

from . import _core
from .env import AutobioEnv
from .vector import AutobioVectorEnv


def core_rate(task, steps, size):
    env = _core.Env(task, 0, size)
    hold = env.hold_action()
    env.frames()
    start = time.perf_counter()
    for _ in range(steps):
        env.frames()
        _r, te, tr, _e = env.step(hold)
        if te or tr:
            env.reset(env.seed + 1)
            hold = env.hold_action()
    return time.perf_counter() - start


def gym_rate(task, steps, size):
    env = AutobioEnv(task, image_size=size)
    env.reset(seed=0)
    hold = np.asarray(env._core.hold_action())
    start = time.perf_counter()
    for _ in range(steps):
        _obs, _r, te, tr, _info = env.step(hold)
        if te or tr:
            env.reset()
            hold = np.asarray(env._core.hold_action())
    return time.perf_counter() - start


def vector_rate(task, steps, size, n):
    venv = AutobioVectorEnv(task, num_envs=n, image_size=size)
    venv.reset(seed=0)
    probe = _core.Env(task, 0, size)
    holds = np.stack([_hold(probe, s) for s in range(n)])
    start = time.perf_counter()
    for _ in range(steps):
        venv.step(holds)
    seconds = time.perf_counter() - start
    venv.close()
    return seconds


def _hold(env, seed):
    env.reset(seed)
    return env.hold_action()


def main():
    p = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    p.add_argument("--task", default="thermal_cycler.close_lid")
    p.add_argument("--steps", type=int, default=600)
    p.add_argument("--image-size", default="224x224")
    p.add_argument("--num-envs", default="1,2,4")
    a = p.parse_args()
    w, h = (int(v) for v in a.image_size.split("x"))
    size = (w, h)

    def emit(mode, seconds, steps, n=1):
        print(json.dumps({"mode": mode, "num_envs": n, "steps": steps, "seconds": seconds,
                          "steps_per_s": steps / seconds}), flush=True)

    # A first, untimed pass warms the scene build and the renderer; the single-environment
    # figures are the best of three, as the Rust side's are.
    core_rate(a.task, 20, size)
    emit("core", min(core_rate(a.task, a.steps, size) for _ in range(3)), a.steps)
    emit("gymnasium", min(gym_rate(a.task, a.steps, size) for _ in range(3)), a.steps)
    for n in (int(v) for v in a.num_envs.split(",")):
        emit("vector", vector_rate(a.task, a.steps, size, n), a.steps * n, n)


if __name__ == "__main__":
    main()
