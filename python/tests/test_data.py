"""Reading what autobio writes: recordings as numpy arrays, a LeRobot dataset's task table."""

import numpy as np

import autobio
from conftest import run_autobio


def test_a_recording_loads_as_arrays_with_its_frames(expert_runs):
    folder, results = expert_runs
    episode = results["tube.transfer"]["episodes"][0]
    rec = autobio.load_recording(folder / "tube.transfer_seed0.mcap", images=True)
    steps = episode["control_steps"]
    assert rec.actions.shape == (steps, 7) and rec.actions.dtype == np.float64
    assert rec.states.shape == (steps, 7)
    assert rec.physics.shape[0] == steps + 1
    assert rec.success and rec.verdict["success"] and rec.error is None
    assert rec.trajectory_hash == episode["trajectory_hash"]
    assert rec.control_steps == steps
    assert rec.robots == ["arm"]
    for camera, frames in rec.images.items():
        assert frames.dtype == np.uint8 and frames.ndim == 4 and frames.shape[-1] == 3
        assert len(rec.image_times[camera]) == len(frames) > 0
    # The frames are pictures, not blanks.
    assert rec.images["table_front"][0].std() > 5


def test_a_lerobot_datasets_task_table_in_both_versions(tmp_path):
    for fmt in ("lerobot-v21", "lerobot-v30"):
        out = tmp_path / fmt
        run_autobio(
            "demo", "--protocol", "protocols/thermal_cycler/close_lid.toml",
            "--protocol", "protocols/centrifuge_5430/close_lid.toml",
            "--episodes", 1, "--format", fmt, "--size", "32x32", "--codec", "h264", "--out", out,
        )
        table = autobio.dataset_tasks(out)
        assert sorted(table) == [0, 1], table
        assert "close the lid of the thermal cycler" in table.values()
