"""Reading what autobio writes, without the glue users write today: a recorded episode (the MCAP
files of ``autobio eval --record`` / ``autobio demo``) as numpy arrays, and a LeRobot dataset's
task table (either version autobio writes: v2.1's ``tasks.jsonl``, v3.0's ``tasks.parquet``)."""

import json
from dataclasses import dataclass, field

import numpy as np

from . import _core


@dataclass
class Recording:
    """One recorded episode.

    ``actions`` (T, A) and ``states`` (T, S) are float64, one row per control step, every
    robot's block concatenated in task order (``robots``); ``physics_times`` (T+1,) and
    ``physics`` (T+1, Q) are MuJoCo's state before each step and at the end; ``labware`` is each
    recorded item state list with its time; ``trajectory_hash``, ``control_steps`` and ``error``
    are the episode's end as the runtime recorded it; ``images`` maps a camera to its frames, (T, H, W, 3)
    uint8, when loaded with ``images=True``; ``task``, ``instance`` and ``verdict`` are the
    compiled task, the seed's draw and the judge's verdict as dicts."""

    task: dict
    instance: dict
    verdict: dict | None
    robots: list
    actions: np.ndarray
    states: np.ndarray
    physics_times: np.ndarray
    physics: np.ndarray
    labware: list
    duration_s: float
    trajectory_hash: str | None = None
    control_steps: int | None = None
    error: str | None = None
    images: dict = field(default_factory=dict)
    image_times: dict = field(default_factory=dict)

    @property
    def seed(self):
        return self.instance.get("seed")

    @property
    def task_id(self):
        return self.task.get("id")

    @property
    def success(self):
        return bool(self.verdict and self.verdict.get("success"))


def load_recording(path, images=False):
    """A recorded episode (MCAP) as a :class:`Recording` of numpy arrays. ``images=True`` also
    decodes every camera frame (PNG) into (T, H, W, 3) uint8 arrays."""
    raw = _core.read_recording(str(path))
    times, physics = raw["physics"]
    end = json.loads(raw["verdict"]) if raw["verdict"] else {}
    rec = Recording(
        task=json.loads(raw["task"]),
        instance=json.loads(raw["instance"]),
        verdict=end.get("verdict"),
        robots=list(raw["robots"]),
        actions=_matrix(raw["actions"]),
        states=_matrix(raw["states"]),
        physics_times=np.asarray(times, dtype=np.float64),
        physics=_matrix(physics),
        labware=[(t, json.loads(s)) for t, s in raw["labware"]],
        duration_s=float(raw["duration_s"]),
        trajectory_hash=end.get("trajectory_hash"),
        control_steps=end.get("control_steps"),
        error=end.get("error"),
    )
    if images:
        for camera, (stamps, pngs) in raw["images"].items():
            frames = []
            for png in pngs:
                w, h, rgb = _core.decode_png(png)
                frames.append(np.frombuffer(rgb, dtype=np.uint8).reshape(h, w, 3))
            rec.images[camera] = np.stack(frames) if frames else np.zeros((0, 0, 0, 3), np.uint8)
            rec.image_times[camera] = np.asarray(stamps, dtype=np.float64)
    return rec


def dataset_tasks(root):
    """A LeRobot dataset's task table as ``{task_index: task}`` (the instruction text)."""
    return dict(_core.dataset_tasks(str(root)))


def _matrix(rows):
    if not rows:
        return np.zeros((0, 0), dtype=np.float64)
    return np.asarray(rows, dtype=np.float64)
