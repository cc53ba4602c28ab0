from typing import Any

import gymnasium
import numpy as np
from numpy.typing import ArrayLike, NDArray

from . import _core

OBS_TYPES: tuple[str, ...]

def image_size_pair(image_size: int | tuple[int, int] | None) -> tuple[int, int] | None: ...
def make(
    task: str,
    seed: int | None = None,
    image_size: int | tuple[int, int] | None = (224, 224),
    **kwargs: Any,
) -> AutobioEnv: ...

class AutobioEnv(gymnasium.Env[dict[str, Any], NDArray[np.float64]]):
    metadata: dict[str, Any]
    render_mode: str | None
    obs_type: str
    instruction_in_obs: bool
    seed_stride: int
    clip_actions: bool
    task_id: str
    camera_names: list[str]
    camera_keys: list[str]
    state_names: list[str]
    action_names: list[str]
    environment_state_names: list[str]
    _core: _core.Env
    _max_episode_steps: int
    def __init__(
        self,
        task: str,
        image_size: int | tuple[int, int] | None = (224, 224),
        render_mode: str | None = "rgb_array",
        obs_type: str = "pixels_agent_pos",
        instruction_in_obs: bool = False,
        seed_stride: int = 1,
        clip_actions: bool = False,
    ) -> None: ...
    @property
    def task_description(self) -> str: ...
    @property
    def task(self) -> str: ...
    @property
    def episode_seed(self) -> int | None: ...
    @property
    def trajectory_hash(self) -> str: ...
    def reset(
        self, *, seed: int | None = None, options: dict[str, Any] | None = None
    ) -> tuple[dict[str, Any], dict[str, Any]]: ...
    def step(
        self, action: ArrayLike
    ) -> tuple[dict[str, Any], float, bool, bool, dict[str, Any]]: ...
    def render(self) -> NDArray[np.uint8] | None: ...
    def close(self) -> None: ...
    def verdict(self) -> dict[str, Any]: ...
    def labware(self) -> list[dict[str, Any]]: ...
    def environment_state(self) -> NDArray[np.float64]: ...
