"""autobio: lab-protocol robot tasks on MuJoCo, from Python.

The Rust core (``autobio._core``) compiles protocols and steps the simulation; this package
shapes it for the tools VLA researchers use:

- ``autobio.make(task, seed=..., image_size=...)``: a gymnasium environment for a shipped task id
  (``autobio.tasks()``) or a protocol file; every shipped task that simulates (all but those
  whose labware has no model yet) is also registered with gymnasium as ``autobio/<task id>-v0`` (``gymnasium.make("autobio/thermal_cycler.close_lid-v0")``), with a
  vector entry point (``gymnasium.make_vec(..., vectorization_mode="vector_entry_point")``) that
  steps N episodes on threads in Rust.
- ``autobio.benchmark.AutobioBenchmark``: the benchmark class for allenai's vla-eval
  (``autobio.benchmark.config_path()`` is a ready config).
- ``autobio.load_recording(path)``: a recorded episode (MCAP) as numpy arrays;
  ``autobio.dataset_tasks(root)``: a LeRobot dataset's task table.
- With ``lerobot`` 0.4 installed (``autobio[lerobot]``): ``autobio.lerobot`` (a checkpoint with its
  processors; the ``autobio`` env type for ``lerobot-eval``), ``python -m autobio.serve`` (a
  checkpoint served to ``autobio eval --model``) and ``python -m autobio.diagnose``.

Episodes are ``autobio eval``'s: the same seed and actions give the same episode, outcome and
trajectory hash.
"""

from . import _core
from ._core import ProtocolError
from .data import Recording, dataset_tasks, load_recording
from .env import AutobioEnv, make
from .vector import AutobioVectorEnv, make_vec

__version__ = _core.__version__

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


def tasks(simulated_only=True):
    """Every shipped task, as dicts: ``id``, ``file``, ``level``, ``instruction``, ``stages``
    (each stage's instruction), ``robots`` ((name, model) pairs), ``cameras``, ``state_names``,
    ``action_names`` (the observation and action layouts), ``time_limit_s``, ``control_dt``,
    ``max_steps``, ``params`` (names drawn per seed) and ``simulated``. With
    ``simulated_only=False``, also the tasks that compile but whose labware has no model yet."""
    return [t for t in _core.tasks() if t["simulated"] or not simulated_only]


def _register():
    import gymnasium

    for t in tasks():
        gid = f"autobio/{t['id']}-v0"
        if gid in gymnasium.registry:
            continue
        gymnasium.register(
            id=gid,
            entry_point="autobio.env:AutobioEnv",
            vector_entry_point="autobio.vector:AutobioVectorEnv",
            kwargs={"task": t["id"]},
            max_episode_steps=t["max_steps"],
        )


_register()
