"""autobio as a benchmark for allenai's vla-eval (0.8): ``AutobioBenchmark``, a
``StepBenchmark`` over the gymnasium environment, loaded by import string
(``autobio.benchmark:AutobioBenchmark``). ``config_path()`` is the config this package ships
(``python -m autobio.benchmark`` prints it); run it with
``vla-eval run -c $(python -m autobio.benchmark) --no-docker --server-url ws://HOST:PORT``.

Tasks are one per (task id, seed): ``{"name": <task id>, "suite": "autobio", "id": <task id>,
"seed": <seed>, "autobio_version": ...}``, so the model server's ``episode_start`` names the task
and seed, and vla-eval's aggregate groups episodes by task id, each episode naming its seed and
the autobio version. Keep ``episodes_per_task: 1``; more repeats each seed (runs of a
stochastic model).

Observations are what autobio's own vla-eval client sends (``autobio eval --wire vla-eval``):
``images`` (camera to uint8 (H, W, 3)), ``states`` (float64, the state layout) and
``task_description``. The action is the server's ``actions`` (the action layout; a chunk's first
row is taken). An episode ends when autobio's judge ends it; its result is ``success``, the task's
``score`` and the ``seed``.
"""

import os

import numpy as np

from . import __version__, _core
from .env import AutobioEnv

try:
    from vla_eval.benchmarks.base import StepBenchmark, StepResult
except ImportError as e:  # pragma: no cover - the class needs vla-eval
    raise ImportError("autobio.benchmark needs vla-eval: pip install 'autobio[vla-eval]'") from e


def config_path():
    """The vla-eval config this package ships (``configs/vla_eval.yaml``)."""
    return os.path.join(os.path.dirname(__file__), "configs", "vla_eval.yaml")


class AutobioBenchmark(StepBenchmark):
    """autobio tasks for vla-eval (see the module docstring).

    ``tasks``: shipped task ids or protocol files (default: the paper's seven simulated tasks of
    ``suites/paper.toml``); ``seeds``: the episode seeds (default ``range(seed, seed + episodes)``);
    ``image_size``: [width, height] of every camera."""

    render_backends = frozenset({"gpu", "cpu"})

    def __init__(self, tasks=None, seeds=None, seed=0, episodes=10, image_size=(224, 224)):
        super().__init__()
        self.task_ids = list(tasks) if tasks else DEFAULT_TASKS
        self.seeds = [int(s) for s in seeds] if seeds is not None else list(
            range(int(seed), int(seed) + int(episodes))
        )
        self.image_size = tuple(image_size)
        self._envs = {}
        self._env = None

    @classmethod
    def configure_render(cls, mode):
        # autobio draws with EGL (Mesa on the CPU, or a GPU's) whichever mode: nothing to set.
        return {}

    def get_tasks(self):
        return [
            {
                "name": t,
                "suite": "autobio",
                "id": t,
                "seed": s,
                "autobio_version": __version__,
            }
            for t in self.task_ids
            for s in self.seeds
        ]

    def get_metadata(self):
        steps = [_core.task_info(t)["max_steps"] for t in self.task_ids]
        return {"max_steps": max(steps), "autobio_version": __version__}

    def get_metric_keys(self):
        return {"success": "mean", "score": "mean"}

    def reset(self, task):
        # One environment per task, kept: a seed of the same task reuses its scene and renderer.
        env = self._envs.get(task["id"])
        if env is None:
            env = self._envs[task["id"]] = AutobioEnv(task["id"], image_size=self.image_size)
        self._env = env
        obs, _info = env.reset(seed=int(task["seed"]))
        return obs

    def step(self, action):
        raw = action.get("actions", action.get("action")) if isinstance(action, dict) else action
        raw = np.asarray(raw, dtype=np.float64)
        if raw.ndim == 2:
            raw = raw[0]
        obs, reward, terminated, truncated, info = self._env.step(raw.reshape(-1))
        return StepResult(obs=obs, reward=reward, done=terminated or truncated, info=info)

    def make_obs(self, raw_obs, task):
        return {
            "images": dict(raw_obs["pixels"]),
            "states": raw_obs["agent_pos"],
            "task_description": self._env.task_description,
        }

    def get_step_result(self, step_result):
        info = step_result.info or {}
        return {
            "success": bool(info.get("is_success", False)),
            "score": float(step_result.reward) if step_result.done else 0.0,
            "seed": int(self._env.episode_seed),
        }

    def cleanup(self):
        for env in self._envs.values():
            env.close()
        self._envs.clear()


# The paper's evaluated tasks autobio simulates (suites/paper.toml).
DEFAULT_TASKS = [
    "thermal_cycler.close_lid",
    "thermal_cycler.open_lid",
    "tube.pick_up",
    "tube.transfer",
    "tube.unscrew_cap",
    "tube.screw_cap",
    "thermal_mixer.set_parameters",
    "centrifuge.insert_symmetric",
]


if __name__ == "__main__":
    print(config_path())
