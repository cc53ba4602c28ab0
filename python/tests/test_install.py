"""The wheel `make setup` builds installs with pip into a fresh virtual environment on this
machine's Python (its dependencies from the wheelhouse setup fetched: no network) and runs a task
from any folder, with no variables exported (MuJoCo and the robot models are found the way the CLI
finds them); `help()` shows the package's docs; the type stubs match the package."""

import glob
import os
import subprocess
import sys
import venv

from conftest import ROOT

import autobio


def test_the_wheel_installs_into_a_fresh_environment_and_runs_a_task(tmp_path):
    wheels = glob.glob(str(ROOT / ".deps/dist/autobio-*.whl"))
    assert len(wheels) == 1, wheels
    env_dir = tmp_path / "venv"
    venv.EnvBuilder(with_pip=True).create(env_dir)
    python = str(env_dir / "bin/python")
    clean = {k: v for k, v in os.environ.items()
             if not k.startswith(("LD_", "MUJOCO", "AUTOBIO", "PYTHON", "CARGO"))}
    install = subprocess.run(
        [python, "-m", "pip", "install", "-q", "--disable-pip-version-check", "--no-index",
         "--find-links", str(ROOT / ".deps/wheelhouse"), wheels[0]],
        capture_output=True, text=True, env=clean,
    )
    assert install.returncode == 0, install.stderr
    script = (
        "import autobio, gymnasium\n"
        "env = gymnasium.make('autobio/thermal_cycler.close_lid-v0', image_size=(32, 32))\n"
        "obs, info = env.reset(seed=0)\n"
        "print(autobio.__file__, obs['pixels']['table_front'].std() > 1, info['instruction'])\n"
    )
    run = subprocess.run([python, "-c", script], capture_output=True, text=True, env=clean,
                         cwd=tmp_path)
    assert run.returncode == 0, run.stderr
    where, drawn, instruction = run.stdout.split(" ", 2)
    assert where.startswith(str(env_dir)) and drawn == "True"
    assert instruction.strip() == "close the lid of the thermal cycler"


def test_help_shows_the_docs():
    for thing, words in [
        (autobio, "gymnasium"),
        (autobio.AutobioEnv, "LeRobot"),
        (autobio.AutobioVectorEnv, "threads"),
        (autobio._core.Env, "same seed"),
        (autobio._core.Env.step, "reward, terminated, truncated"),
        (autobio.load_recording, "numpy"),
    ]:
        text = thing.__doc__ or ""
        if thing in (autobio.AutobioEnv, autobio.AutobioVectorEnv):
            text += sys.modules[thing.__module__].__doc__
        assert words in text, (thing, text[:200])


def test_the_type_stubs_match_the_installed_package(tmp_path):
    allowlist = ROOT / "python/tests/stubtest-allowlist.txt"
    run = subprocess.run(
        [sys.executable, "-m", "mypy.stubtest", "autobio", "--allowlist", str(allowlist)],
        capture_output=True, text=True, cwd=tmp_path,
    )
    assert run.returncode == 0, run.stdout + run.stderr
