from dataclasses import dataclass
from typing import Any, TextIO

import numpy as np

STATE: str
ENVIRONMENT: str
ACTION: str
STD_FLOOR: float
PERSIST: int

@dataclass
class Episode:
    index: int
    task: str
    seed: int
    state: np.ndarray
    environment_state: np.ndarray | None
    action: np.ndarray

@dataclass
class Dataset:
    root: str
    episodes: list[Episode]
    info: dict[str, Any]
    def names(self, key: str) -> list[str]: ...
    def frames(self, key: str) -> np.ndarray: ...

def read_dataset(root: str) -> Dataset: ...
def alignment(
    dataset: Dataset, episodes: int | None = None, shift: int = 0
) -> list[dict[str, Any]]: ...
def open_loop(runner: Any, train: Dataset, held_out: Dataset) -> dict[str, Any]: ...
def drift(
    runner: Any,
    train: Dataset,
    held_out: Dataset,
    task: str,
    seeds: list[int],
    threshold_quantile: float = 0.99,
) -> dict[str, Any]: ...
def main(argv: list[str] | None = None) -> int: ...
