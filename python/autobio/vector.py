"""gymnasium's vector API over autobio: ``AutobioVectorEnv`` steps N episodes of one task at once,
each on its own thread in Rust (``autobio._core.VecEnv``; the GIL is released while they run),
not N Python processes. ``gymnasium.make_vec("autobio/<task>-v0", num_envs=N,
vectorization_mode="vector_entry_point")`` makes one; so does ``autobio.make_vec``.

Autoreset follows gymnasium 1.x's default (``AutoresetMode.NEXT_STEP``): the step after a
sub-environment's episode ends resets it (its action is ignored; reward 0, not terminated or
truncated). Seeds: ``reset(seed=s)`` starts sub-environment ``i`` on episode ``s + i``; each
autoreset goes on to that sub-environment's seed plus ``num_envs``, so N sub-environments cover
seeds ``s, s+1, ...`` without repeating one. The episodes are the single environment's: the
same seed and actions give the same trajectory hash.

Observations are batched (``pixels/<camera>``: (N, H, W, 3) uint8, ``agent_pos``: (N, S),
``environment_state``: (N, E) with ``obs_type="environment_state_agent_pos"``, which draws no
camera; ``AutobioEnv`` lists the observation types);
``infos`` holds per-step arrays (``is_success``, ``score``, ``seed``, ``stage``,
``trajectory_hash``, ``instruction``, ``error``) with gymnasium's ``_<key>`` masks.
"""

import numbers

import numpy as np
from gymnasium.vector import AutoresetMode, VectorEnv
from gymnasium.vector.utils import batch_space

from . import _core
from .env import AutobioEnv, image_size_pair


def make_vec(task, num_envs, image_size=(224, 224), **kwargs):
    """A vector environment of ``num_envs`` episodes of ``task`` (a shipped task id or a protocol
    file), each on its own thread. ``image_size``: an int (square) or (width, height)."""
    return AutobioVectorEnv(task, num_envs=num_envs, image_size=image_size, **kwargs)


class AutobioVectorEnv(VectorEnv):
    """N episodes of one autobio task, stepped on N threads (see the module docstring)."""

    def __init__(
        self,
        task,
        num_envs=1,
        image_size=(224, 224),
        render_mode="rgb_array",
        obs_type="pixels_agent_pos",
        max_episode_steps=None,
    ):
        # `max_episode_steps` is what gymnasium.make_vec passes from the registration: the time
        # limit over the control period plus one, so autobio's judge ends every episode first.
        # One single environment describes the spaces; it is closed straight away.
        probe = AutobioEnv(task, image_size=image_size, render_mode=render_mode, obs_type=obs_type)
        self.single_observation_space = probe.observation_space
        self.single_action_space = probe.action_space
        self.camera_names = probe.camera_names
        self.camera_keys = probe.camera_keys
        self.task_id = probe.task_id
        self._shape = probe._shape
        self._max_episode_steps = probe._max_episode_steps
        self.metadata = {
            "render_modes": ["rgb_array"],
            "render_fps": probe.metadata["render_fps"],
            "autoreset_mode": AutoresetMode.NEXT_STEP,
        }
        probe.close()
        self.num_envs = num_envs
        self.render_mode = render_mode
        self.obs_type = obs_type
        self.observation_space = batch_space(self.single_observation_space, num_envs)
        self.action_space = batch_space(self.single_action_space, num_envs)
        self._core = _core.VecEnv(
            str(task), num_envs, image_size_pair(image_size), obs_type.startswith("pixels")
        )
        self._seeds = None
        self._autoreset = np.zeros(num_envs, dtype=bool)
        self._last = None

    @property
    def task_description(self):
        """Each sub-environment's running instruction."""
        return [r["instruction"] for r in self._last] if self._last else []

    def reset(self, *, seed=None, options=None):
        one = seed is None or isinstance(seed, numbers.Integral)
        super().reset(seed=int(seed) if one and seed is not None else None)
        if seed is None:
            base = 0 if self._seeds is None else int(self._seeds.max()) + 1
            seeds = [base + i for i in range(self.num_envs)]
        elif isinstance(seed, numbers.Integral):
            seeds = [int(seed) + i for i in range(self.num_envs)]
        else:
            seeds = [int(s) for s in seed]
            if len(seeds) != self.num_envs:
                raise ValueError(f"{len(seeds)} seeds for {self.num_envs} environments")
        self._seeds = np.asarray(seeds, dtype=np.int64)
        replies = self._core.batch([], [int(s) for s in seeds])
        self._autoreset[:] = False
        self._last = replies
        return self._observations(replies), self._infos(replies)

    def step(self, actions):
        if self._seeds is None:
            raise RuntimeError("call reset() before step()")
        actions = np.asarray(actions, dtype=np.float64).reshape(self.num_envs, -1)
        resets = [
            int(self._seeds[i] + self.num_envs) if self._autoreset[i] else None
            for i in range(self.num_envs)
        ]
        for i, s in enumerate(resets):
            if s is not None:
                self._seeds[i] = s
        replies = self._core.batch(actions.tolist(), resets)
        rewards = np.array([r["reward"] for r in replies], dtype=np.float64)
        terminated = np.array([r["terminated"] for r in replies], dtype=bool)
        truncated = np.array([r["truncated"] for r in replies], dtype=bool)
        self._autoreset = terminated | truncated
        self._last = replies
        return self._observations(replies), rewards, terminated, truncated, self._infos(replies)

    def render(self):
        """Each sub-environment's cameras side by side, one frame per sub-environment."""
        if not self._last:
            return None
        return tuple(
            np.concatenate([self._frame(f) for f in r["frames"]], axis=1) for r in self._last
        )

    def close_extras(self, **kwargs):
        if self._core is not None:
            self._core.close()
            self._core = None

    def _frame(self, f):
        return np.frombuffer(f, dtype=np.uint8).reshape(self._shape)

    def _observations(self, replies):
        obs = {}
        if self.obs_type.startswith("pixels"):
            obs["pixels"] = {
                c: np.stack([self._frame(r["frames"][k]) for r in replies])
                for k, c in enumerate(self.camera_keys)
            }
        if "environment_state" in self.obs_type:
            obs["environment_state"] = np.array(
                [r["environment_state"] for r in replies], dtype=np.float64
            )
        if self.obs_type.endswith("agent_pos"):
            obs["agent_pos"] = np.array([r["state"] for r in replies], dtype=np.float64)
        return obs

    def _infos(self, replies):
        n = self.num_envs
        every = np.ones(n, dtype=bool)
        infos = {
            "is_success": np.array([r["is_success"] for r in replies], dtype=bool),
            "score": np.array([r["score"] for r in replies], dtype=np.float64),
            "seed": np.array([r["seed"] for r in replies], dtype=np.int64),
            "stage": np.array([r["stage"] for r in replies], dtype=np.int64),
            "control_steps": np.array([r["control_steps"] for r in replies], dtype=np.int64),
            "trajectory_hash": np.array([r["trajectory_hash"] for r in replies], dtype=object),
            "instruction": np.array([r["instruction"] for r in replies], dtype=object),
        }
        for key in list(infos):
            infos[f"_{key}"] = every
        errors = [r["error"] for r in replies]
        if any(e is not None for e in errors):
            infos["error"] = np.array(errors, dtype=object)
            infos["_error"] = np.array([e is not None for e in errors], dtype=bool)
        return infos
