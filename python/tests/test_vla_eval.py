"""vla-eval's own orchestrator (`vla-eval run`, 0.8 from PyPI) runs the autobio benchmark
against the reference vla-eval model server (tests/servers/vla_eval_server.py, built on
vla-eval's PredictModelServer) replaying the scripted expert's recorded actions."""

import json
import selectors
import subprocess
import sys

import yaml

import autobio
from autobio.benchmark import AutobioBenchmark, config_path
from conftest import ROOT


# How long the reference server may take to come up (Python and numpy importing on a loaded
# 2-core machine take a few seconds): a server that never says it listens fails the test, not
# hangs it.
SERVER_START_DEADLINE_S = 60


def first_line(proc, deadline_s=SERVER_START_DEADLINE_S):
    """The process's first line of output, or a failure once `deadline_s` pass without one."""
    sel = selectors.DefaultSelector()
    sel.register(proc.stdout, selectors.EVENT_READ)
    if not sel.select(timeout=deadline_s):
        proc.kill()
        raise AssertionError(f"the server printed nothing in {deadline_s} s: {proc.stderr.read()}")
    return proc.stdout.readline()


def test_the_shipped_config_names_the_benchmark_class():
    config = yaml.safe_load(open(config_path()))
    entry = config["benchmarks"][0]
    assert entry["benchmark"] == "autobio.benchmark:AutobioBenchmark"
    bench = AutobioBenchmark(**entry["params"])
    ids = {t["id"] for t in autobio.tasks()}
    assert {t["id"] for t in bench.get_tasks()} <= ids
    assert bench.get_metadata()["max_steps"] >= 1576


def test_vla_eval_runs_the_expert_to_success_through_its_orchestrator(expert_runs, tmp_path):
    folder, results = expert_runs
    server = subprocess.Popen(
        [str(ROOT / ".deps/servers/bin/python"), str(ROOT / "tests/servers/vla_eval_server.py"),
         "--recordings", str(folder)],
        stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
    )
    try:
        line = first_line(server)
        assert line.startswith("listening on "), line + server.stderr.read()
        url = line.split()[-1]
        config = tmp_path / "autobio.yaml"
        config.write_text(yaml.safe_dump({
            "server": {"url": url, "timeout": 60},
            "benchmarks": [{
                "benchmark": "autobio.benchmark:AutobioBenchmark",
                "name": "autobio",
                "episodes_per_task": 1,
                "params": {"tasks": ["thermal_cycler.close_lid", "tube.transfer"], "seeds": [0, 1]},
            }],
        }))
        out = tmp_path / "results"
        run = subprocess.run(
            [sys.executable, "-m", "vla_eval.cli.main", "run", "-c", str(config), "--no-docker",
             "--server-url", url, "--output-dir", str(out)],
            capture_output=True, text=True, timeout=600,
        )
        assert run.returncode == 0, run.stdout + run.stderr
    finally:
        server.terminate()
        server.wait(10)
    aggregate = json.loads((out / "autobio_aggregate.json").read_text())
    assert aggregate["num_episodes_total"] == 4 and aggregate["mean_success"] == 1.0, aggregate
    by_task = {t["task"]: t for t in aggregate["tasks"]}
    assert set(by_task) == {"thermal_cycler.close_lid", "tube.transfer"}
    for task, entry in by_task.items():
        assert entry["mean_success"] == 1.0
        seeds = sorted(e["seed"] for e in entry["episodes"])
        assert seeds == [0, 1]
        for e in entry["episodes"]:
            assert e["autobio_version"] == autobio.__version__ and e["id"] == task
            assert e["metrics"]["success"] is True and e["metrics"]["score"] == 1.0
