"""The gymnasium environment over one autobio task (``autobio._core.Env``).

Observations follow LeRobot's gym convention (``obs_type="pixels_agent_pos"``, as gym-aloha and
gym-pusht): ``{"pixels": {<camera key>: uint8 (H, W, 3)}, "agent_pos": float64 (S,)}``, the state
being every robot's joints in task order (``state_names``). A camera key is the task camera's
name with ``/`` as ``_`` (``arm/wrist`` is ``arm_wrist``; ``camera_keys``), as autobio's datasets
name their image features. ``obs_type="pixels"`` drops
``agent_pos``; ``instruction_in_obs=True`` adds the running stage's instruction as ``"instruction"``
(a ``Text`` space).

State-based policies (gym-pusht's convention, LeRobot's ``observation.environment_state``):
``obs_type="environment_state_agent_pos"`` gives ``{"environment_state": float64 (E,),
"agent_pos": float64 (S,)}`` and draws no camera at all; ``"pixels_environment_state_agent_pos"``
gives all three. The environment state is privileged (the poses, joints, panel values and
volumes of the items the task's success checks read, then the drawn parameters), in the task's
fixed layout ``environment_state_names`` (docs/python.md); a model that reads it is a state
model, ranked apart from vision models. The instruction is always in ``info["instruction"]`` and in the
``task_description`` / ``task`` attributes LeRobot's eval reads.

The action is every robot's action concatenated in task order (``action_names``: arm joint
targets in rad, then the gripper command), float64 within the actuators' ranges.

Reward: the task's score when the episode ends (0 before), ``terminated`` when it succeeded,
``truncated`` when a stage's or the task's time ran out, exactly as ``autobio eval`` judges.
``info["is_success"]`` is the judge's verdict at every step. A simulation that becomes unstable
ends the episode (``truncated``, reward 0: an episode that ends in an error scores 0, as in
``autobio eval``) with its reason in ``info["error"]``. An action of the wrong length, not finite or
outside its range raises ``ValueError`` before anything moves; the episode goes on.

Seeds are ``autobio eval``'s episode seeds: ``reset(seed=s)`` is episode ``s``; ``reset()``
with no seed goes on to the next seed (the previous one plus ``seed_stride``, 1 by default).
"""

import json
import string

import gymnasium
import numpy as np
from gymnasium import spaces

from . import _core

_TEXT = string.printable


OBS_TYPES = (
    "pixels_agent_pos",
    "pixels",
    "environment_state_agent_pos",
    "pixels_environment_state_agent_pos",
)


def image_size_pair(image_size):
    """``image_size`` as (width, height): an int is a square camera, a pair is (width,
    height), ``None`` stays ``None`` (the task's own camera spec)."""
    if image_size is None:
        return None
    if isinstance(image_size, (int, np.integer)) and not isinstance(image_size, bool):
        size = (int(image_size), int(image_size))
    else:
        sides = () if isinstance(image_size, (str, bytes)) else image_size
        try:
            size = tuple(int(x) for x in sides)
        except (TypeError, ValueError):
            size = ()
        if not size:
            raise TypeError(
                f"image_size {image_size!r}: give an int (square) or (width, height)"
            )
        if len(size) != 2:
            raise ValueError(f"image_size {image_size!r}: give an int or (width, height)")
    if min(size) < 1 or max(size) > 4096:
        raise ValueError(f"image_size {image_size!r}: each side between 1 and 4096 pixels")
    return size


def make(task, seed=None, image_size=(224, 224), **kwargs):
    """A gymnasium environment for ``task`` (a shipped task id or a protocol file), reset to
    episode ``seed`` when one is given. ``image_size`` is an int for square cameras or (width,
    height) for every camera (``None``: the task's camera spec). Other keywords go to
    ``AutobioEnv`` (``obs_type``, ``instruction_in_obs``, ``seed_stride``, ``clip_actions``)."""
    env = AutobioEnv(task, image_size=image_size, **kwargs)
    if seed is not None:
        env.reset(seed=seed)
    return env


class AutobioEnv(gymnasium.Env):
    """One autobio task as a gymnasium 1.x environment (see the module docstring)."""

    metadata = {"render_modes": ["rgb_array"], "render_fps": 50}

    def __init__(
        self,
        task,
        image_size=(224, 224),
        render_mode="rgb_array",
        obs_type="pixels_agent_pos",
        instruction_in_obs=False,
        seed_stride=1,
        clip_actions=False,
    ):
        if render_mode not in (None, "rgb_array"):
            raise ValueError(f"render_mode {render_mode!r}: autobio draws rgb_array frames only")
        if obs_type not in OBS_TYPES:
            raise ValueError(f"obs_type {obs_type!r}: use one of {', '.join(OBS_TYPES)}")
        self._core = _core.Env(str(task), 0, image_size_pair(image_size))
        self.render_mode = render_mode
        self.obs_type = obs_type
        self.instruction_in_obs = instruction_in_obs
        self.seed_stride = seed_stride
        self.clip_actions = clip_actions
        self._episode_seed = None
        core = self._core
        self.task_id = core.id
        self.camera_names = list(core.camera_names)
        # LeRobot's feature keys are `pixels/<camera>`: a `/` in a camera name becomes `_`, as
        # autobio's datasets name them (`observation.images.arm_wrist`).
        self.camera_keys = [c.replace("/", "_") for c in self.camera_names]
        self.state_names = list(core.state_names)
        self.action_names = list(core.action_names)
        self.environment_state_names = list(core.environment_state_names)
        self.metadata = dict(self.metadata, render_fps=round(1.0 / core.control_dt))
        self._max_episode_steps = core.max_steps
        w, h = core.image_size
        self._shape = (h, w, 3)
        obs = {}
        if self._pixels_in_obs:
            obs["pixels"] = spaces.Dict(
                {c: spaces.Box(0, 255, self._shape, dtype=np.uint8) for c in self.camera_keys}
            )
        if "environment_state" in obs_type:
            n = len(self.environment_state_names)
            obs["environment_state"] = spaces.Box(-np.inf, np.inf, (n,), dtype=np.float64)
        if obs_type.endswith("agent_pos"):
            n = len(self.state_names)
            obs["agent_pos"] = spaces.Box(-np.inf, np.inf, (n,), dtype=np.float64)
        if instruction_in_obs:
            # Printable ASCII and every other character the task's instructions and parameter
            # values use (`°C`, `µL`).
            extra = sorted({c for c in core.task_json() if c not in _TEXT and c.isprintable()})
            obs["instruction"] = spaces.Text(max_length=1024, charset=_TEXT + "".join(extra))
        self.observation_space = spaces.Dict(obs)
        low = np.asarray(core.action_low, dtype=np.float64)
        high = np.asarray(core.action_high, dtype=np.float64)
        self.action_space = spaces.Box(low, high, dtype=np.float64)

    # What LeRobot's eval loop reads from a sub-environment.
    @property
    def task_description(self):
        """The running stage's instruction (the seed's parameters filled in)."""
        return self._core.instruction

    @property
    def task(self):
        return self._core.instruction

    @property
    def episode_seed(self):
        """The autobio seed of the running episode (``None`` before the first reset)."""
        return self._episode_seed

    @property
    def trajectory_hash(self):
        return self._core.trajectory_hash

    @property
    def _pixels_in_obs(self):
        return self.obs_type.startswith("pixels")

    def reset(self, *, seed=None, options=None):
        """Starts an episode and returns ``(observation, info)``.

        ``seed`` is the autobio episode seed (``autobio eval``'s: the same seed draws the same
        scene and parameters); without one the next seed is taken (the last plus
        ``seed_stride``; 0 first). ``options`` is accepted for gymnasium and ignored.
        ``info`` holds ``task``, ``seed``, ``instruction``, ``stage``, ``is_success``,
        ``score``, ``time``, ``control_steps``, ``trajectory_hash`` and the drawn ``params``."""
        super().reset(seed=seed)
        if seed is not None:
            episode = int(seed)
        elif self._episode_seed is None:
            episode = 0
        else:
            episode = self._episode_seed + self.seed_stride
        self._core.reset(episode)
        self._episode_seed = episode
        info = self._info()
        info["params"] = dict(self._core.params)
        return self._observation(), info

    def step(self, action):
        """Applies ``action`` for one control step (held for the task's physics substeps) and
        returns ``(observation, reward, terminated, truncated, info)``.

        ``action`` is every robot's action in ``action_names`` order (float, within
        ``action_space``); a wrong length, a value outside its range or not finite raises
        ``ValueError`` and nothing moves (with ``clip_actions=True``, a finite value outside
        its range is clipped to it instead: gymnasium's ``ClipAction``, for loops such as
        ``lerobot-eval`` that send a policy's raw output). ``reward`` is the task's score on
        the step that ends the episode, else 0; ``terminated``: the task succeeded; ``truncated``: a stage's or the
        task's time ran out, or the simulation became unstable (``info["error"]``).
        ``info["is_success"]`` is the judge's verdict now."""
        if self._episode_seed is None:
            raise gymnasium.error.ResetNeeded("call reset() before step()")
        action = np.asarray(action, dtype=np.float64).reshape(-1)
        if self.clip_actions and action.shape == self.action_space.shape:
            action = np.clip(action, self.action_space.low, self.action_space.high)
        reward, terminated, truncated, error = self._core.step(action.tolist())
        info = self._info()
        if error is not None:
            info["error"] = error
        return self._observation(), float(reward), bool(terminated), bool(truncated), info

    def render(self):
        """The task cameras' frames side by side (uint8, H x (W * cameras) x 3)."""
        if self.render_mode is None:
            return None
        return np.concatenate(list(self._pixels().values()), axis=1)

    def close(self):
        self._core = None

    def verdict(self):
        """The judge's verdict so far: success, score and each stage's predicates."""
        return json.loads(self._core.verdict_json())

    def labware(self):
        """Every item's live state (parts, joints, panel values), as the recordings store it."""
        return json.loads(self._core.labware_json())

    def _pixels(self):
        frames = self._core.frames()
        return {
            c: np.frombuffer(f, dtype=np.uint8).reshape(self._shape).copy()
            for c, f in zip(self.camera_keys, frames)
        }

    def environment_state(self):
        """The task's environment state now (``environment_state_names``), float64."""
        return np.asarray(self._core.environment_state(), dtype=np.float64)

    def _observation(self):
        obs = {}
        if self._pixels_in_obs:
            obs["pixels"] = self._pixels()
        if "environment_state" in self.obs_type:
            obs["environment_state"] = self.environment_state()
        if self.obs_type.endswith("agent_pos"):
            obs["agent_pos"] = np.asarray(self._core.state(), dtype=np.float64)
        if self.instruction_in_obs:
            obs["instruction"] = self._core.instruction
        return obs

    def _info(self):
        core = self._core
        success, score = core.outcome()
        return {
            "task": self.task_id,
            "seed": self._episode_seed,
            "instruction": core.instruction,
            "stage": core.stage,
            "is_success": bool(success),
            "score": float(score),
            "time": core.time,
            "control_steps": core.control_steps,
            "trajectory_hash": core.trajectory_hash,
        }
