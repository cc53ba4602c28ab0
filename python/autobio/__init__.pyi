from typing import Any

from ._core import ProtocolError as ProtocolError
from .data import Recording as Recording, dataset_tasks as dataset_tasks, load_recording as load_recording
from .env import AutobioEnv as AutobioEnv, make as make
from .vector import AutobioVectorEnv as AutobioVectorEnv, make_vec as make_vec

__version__: str

def tasks(simulated_only: bool = True) -> list[dict[str, Any]]: ...

__all__ = [
    "AutobioEnv",
    "AutobioVectorEnv",
    "ProtocolError",
    "Recording",
    "dataset_tasks",
    "load_recording",
    "make",
    "make_vec",
    "tasks",
]
