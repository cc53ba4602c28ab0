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
``score`` and the ``seed``. With ``environment_state=True`` the observation also holds
``environment_state`` (float64, the task's privileged state layout; a state-based model).

``get_action_spec`` and ``get_observation_spec`` declare these (vla-eval's ``DimSpec``s), so
the orchestrator checks a server's declared specs before the first episode: the action is
``actions`` (format ``autobio_joint_targets``: each robot's joint position targets in rad, then
its gripper command, in task order; each within its actuator's range), the observation
``image`` (one per camera, ``rgb_hwc_uint8``), ``state`` (``joint_positions``), ``language``
and, when asked, ``environment_state``. Where the tasks' layouts differ, ``dims`` is 0.
"""

import os

import numpy as np

from . import __version__, _core
from .env import AutobioEnv, image_size_pair

try:
    from vla_eval.benchmarks.base import StepBenchmark, StepResult
    from vla_eval.specs import IMAGE_RGB, LANGUAGE, DimSpec
except ImportError as e:  # pragma: no cover - the class needs vla-eval
    raise ImportError("autobio.benchmark needs vla-eval: pip install 'autobio[vla-eval]'") from e


def config_path():
    """The vla-eval config this package ships (``configs/vla_eval.yaml``)."""
    return os.path.join(os.path.dirname(__file__), "configs", "vla_eval.yaml")


class AutobioBenchmark(StepBenchmark):
    """autobio tasks for vla-eval (see the module docstring).

    ``tasks``: shipped task ids or protocol files (default: the paper's seven simulated tasks of
    ``suites/paper.toml``); ``seeds``: the episode seeds (default ``range(seed, seed + episodes)``);
    ``image_size``: an int (square) or [width, height] of every camera; ``environment_state``:
    also send the task's environment state (privileged)."""

    render_backends = frozenset({"gpu", "cpu"})

    def __init__(
        self,
        tasks=None,
        seeds=None,
        seed=0,
        episodes=10,
        image_size=(224, 224),
        environment_state=False,
    ):
        super().__init__()
        self.task_ids = list(tasks) if tasks else DEFAULT_TASKS
        self.seeds = [int(s) for s in seeds] if seeds is not None else list(
            range(int(seed), int(seed) + int(episodes))
        )
        self.image_size = image_size_pair(image_size)
        self.environment_state = bool(environment_state)
        self._infos = [_core.task_info(t) for t in self.task_ids]
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
        steps = [i["max_steps"] for i in self._infos]
        return {"max_steps": max(steps), "autobio_version": __version__}

    def _shared(self, key):
        """The tasks' common layout under ``key`` (a list of names), or None where they differ."""
        first = self._infos[0][key]
        return first if all(i[key] == first for i in self._infos) else None

    def get_action_spec(self):
        names = self._shared("action_names")
        return {
            "actions": DimSpec(
                "actions",
                len(names) if names else 0,
                "autobio_joint_targets",
                # A server's `raw` actions are its checkpoint's own: autobio's layout, taken as is.
                accepts=frozenset({"autobio_joint_targets", "raw"}),
                description="each robot's joint position targets (rad), then its gripper "
                + "command, in task order: "
                + (", ".join(names) if names else "the layout differs between the tasks"),
            )
        }

    def get_observation_spec(self):
        w, h = self.image_size
        cameras = self._shared("cameras")
        state = self._shared("state_names")
        spec = {
            "image": DimSpec(
                "image",
                0,
                IMAGE_RGB.format,
                description=f"{w}x{h} uint8 per camera under `images`: "
                + (", ".join(c.replace("/", "_") for c in cameras) if cameras else "per task"),
            ),
            "state": DimSpec(
                "state",
                len(state) if state else 0,
                "joint_positions",
                description="`states`: " + (", ".join(state) if state else "per task"),
            ),
            "language": LANGUAGE,
        }
        if self.environment_state:
            env = self._shared("environment_state_names")
            spec["environment_state"] = DimSpec(
                "environment_state",
                len(env) if env else 0,
                "autobio_environment_state",
                description="privileged: " + (", ".join(env) if env else "per task"),
            )
        return spec

    def get_metric_keys(self):
        return {"success": "mean", "score": "mean"}

    def reset(self, task):
        # One environment per task, kept: a seed of the same task reuses its scene and renderer.
        env = self._envs.get(task["id"])
        if env is None:
            obs_type = (
                "pixels_environment_state_agent_pos"
                if self.environment_state
                else "pixels_agent_pos"
            )
            env = self._envs[task["id"]] = AutobioEnv(
                task["id"], image_size=self.image_size, obs_type=obs_type
            )
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
        obs = {
            "images": dict(raw_obs["pixels"]),
            "states": raw_obs["agent_pos"],
            "task_description": self._env.task_description,
        }
        if self.environment_state:
            obs["environment_state"] = raw_obs["environment_state"]
        return obs

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
