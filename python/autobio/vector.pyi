from typing import Any

import numpy as np
from gymnasium.vector import VectorEnv
from numpy.typing import ArrayLike, NDArray

def make_vec(
    task: str, num_envs: int, image_size: int | tuple[int, int] | None = (224, 224), **kwargs: Any
) -> AutobioVectorEnv: ...

class AutobioVectorEnv(VectorEnv[dict[str, Any], NDArray[np.float64], NDArray[Any]]):
    camera_names: list[str]
    camera_keys: list[str]
    task_id: str
    obs_type: str
    _max_episode_steps: int
    def __init__(
        self,
        task: str,
        num_envs: int = 1,
        image_size: int | tuple[int, int] | None = (224, 224),
        render_mode: str | None = "rgb_array",
        obs_type: str = "pixels_agent_pos",
        max_episode_steps: int | None = None,
    ) -> None: ...
    @property
    def task_description(self) -> list[str]: ...
    def reset(
        self, *, seed: int | list[int] | None = None, options: dict[str, Any] | None = None
    ) -> tuple[dict[str, Any], dict[str, Any]]: ...
    def step(
        self, actions: ArrayLike
    ) -> tuple[dict[str, Any], NDArray[Any], NDArray[Any], NDArray[Any], dict[str, Any]]: ...
    def render(self) -> tuple[NDArray[np.uint8], ...] | None: ...
    def close_extras(self, **kwargs: Any) -> None: ...
