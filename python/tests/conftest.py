"""Shared fixtures for the Python package's tests. They run in .deps/python-env (made by `make
setup`: the wheel built from this checkout, gymnasium, vla-eval and pytest from PyPI), against the
real `autobio` CLI (AUTOBIO_BIN, else the cargo target folder's release build) and the real
reference model server (tests/servers, in .deps/servers). `make test` runs them after cargo's."""

import json
import os
import subprocess
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]


def autobio_bin():
    if os.environ.get("AUTOBIO_BIN"):
        return os.environ["AUTOBIO_BIN"]
    target = os.environ.get("CARGO_TARGET_DIR", str(ROOT / "target"))
    return str(Path(target) / "release" / "autobio")


def run_autobio(*args, cwd=ROOT):
    out = subprocess.run([autobio_bin(), *map(str, args)], cwd=cwd, capture_output=True, text=True)
    assert out.returncode == 0, f"autobio {' '.join(map(str, args))}:\n{out.stdout}\n{out.stderr}"
    return out


@pytest.fixture(scope="session")
def expert_runs(tmp_path_factory):
    """`autobio eval`'s scripted expert, recorded: seeds 0-1 of the thermal cycler's close and
    of the tube transfer. Returns (folder, {task id: results JSON})."""
    out = tmp_path_factory.mktemp("expert")
    run_autobio(
        "eval",
        "--protocol", "protocols/thermal_cycler/close_lid.toml",
        "--protocol", "protocols/tube/transfer.toml",
        "--episodes", 2, "--seed", 0, "--out", out, "--record",
    )
    results = {}
    for f in out.glob("*.results.json"):
        r = json.loads(f.read_text())
        results[r["task_id"]] = r
    assert set(results) == {"thermal_cycler.close_lid", "tube.transfer"}, results.keys()
    return out, results
