"""Type stubs for autobio's native core (the Rust extension)."""

from typing import Any, final

__all__ = [
    "__version__",
    "ProtocolError",
    "Env",
    "VecEnv",
    "tasks",
    "compile",
    "task_info",
    "read_recording",
    "decode_png",
    "dataset_tasks",
]

__version__: str

class ProtocolError(ValueError):
    """A protocol that cannot be loaded: unknown, unreadable, or with errors (each with its
    file:line:col, code and hint)."""

def tasks() -> list[dict[str, Any]]:
    """Every shipped task (id, file, level, instruction, stages, robots, cameras, layouts,
    time limit, control period, max steps, parameter names, simulated)."""

def task_info(task: str) -> dict[str, Any]:
    """The dict tasks() gives, for a shipped task id or a protocol file."""

def compile(task: str) -> str:
    """The compiled task of a shipped id or a protocol file, as JSON."""

def read_recording(path: str) -> dict[str, Any]:
    """A recording's contents as plain values (see autobio.load_recording)."""

def decode_png(png: bytes) -> tuple[int, int, bytes]:
    """A PNG's (width, height, RGB bytes)."""

def dataset_tasks(root: str) -> list[tuple[int, str]]:
    """A LeRobot dataset's (task_index, task) rows."""

@final
class Env:
    """One task's episodes, stepped by hand."""

    def __new__(cls, task: str, seed: int = 0, image_size: tuple[int, int] | None = None) -> Env: ...
    def reset(self, seed: int) -> None: ...
    def step(self, action: list[float]) -> tuple[float, bool, bool, str | None]: ...
    def state(self) -> list[float]: ...
    def environment_state(self) -> list[float]: ...
    def frames(self) -> list[bytes]: ...
    def outcome(self) -> tuple[bool, float]: ...
    def hold_action(self) -> list[float]: ...
    def verdict_json(self) -> str: ...
    def labware_json(self) -> str: ...
    def task_json(self) -> str: ...
    id: str
    level: str
    seed: int
    instruction: str
    task_instruction: str
    stage: int
    params: dict[str, str]
    time: float
    control_steps: int
    control_dt: float
    time_limit_s: float
    max_steps: int
    done: bool
    trajectory_hash: str
    camera_names: list[str]
    image_size: tuple[int, int]
    state_names: list[str]
    action_names: list[str]
    environment_state_names: list[str]
    action_low: list[float]
    action_high: list[float]

@final
class VecEnv:
    """N episodes of one task on N threads."""

    def __new__(
        cls, task: str, num_envs: int, image_size: tuple[int, int] | None = None, images: bool = True
    ) -> VecEnv: ...
    num_envs: int
    def batch(self, actions: list[list[float]], resets: list[int | None]) -> list[dict[str, Any]]: ...
    def close(self) -> None: ...
