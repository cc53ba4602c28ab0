"""The gymnasium environment: conformance on every shipped task, the same episodes as `autobio
eval`, the end of an episode as eval judges it, and clear errors."""

import json

import gymnasium
import numpy as np
import pytest
from gymnasium.utils.env_checker import check_env

import autobio
from conftest import run_autobio

SHIPPED = [t["id"] for t in autobio.tasks()]


def test_every_shipped_task_is_registered_and_simulated():
    # Every shipped protocol and chain file compiles into a listed task (none dropped); a scene
    # file, which protocols share, is no task.
    files = sorted(str(p.relative_to(autobio_root())) for p in
                   (autobio_root() / "protocols").glob("*/*.toml")
                   if "\n[scene]\n" not in p.read_text())
    assert sorted(t["file"] for t in autobio.tasks(simulated_only=False)) == files
    assert len(SHIPPED) >= 15, SHIPPED
    for t in SHIPPED:
        assert f"autobio/{t}-v0" in gymnasium.registry
    # Every shipped task is simulated now (pipetting last), so each is registered.
    everything = {t["id"]: t for t in autobio.tasks(simulated_only=False)}
    assert [i for i, t in everything.items() if not t["simulated"]] == []
    assert "autobio/pipette.aspirate-v0" in gymnasium.registry


@pytest.mark.parametrize("task", SHIPPED)
def test_check_env_passes(task):
    env = gymnasium.make(f"autobio/{task}-v0", image_size=(64, 48), disable_env_checker=True)
    check_env(env.unwrapped, skip_render_check=False)
    obs, info = env.reset(seed=5)
    space = env.observation_space
    assert set(obs["pixels"]) == set(space["pixels"].spaces)
    for key, img in obs["pixels"].items():
        assert "/" not in key and img.shape == (48, 64, 3) and img.dtype == np.uint8
    assert obs["agent_pos"].shape == (len(env.unwrapped.state_names),)
    assert env.action_space.shape == (len(env.unwrapped.action_names),)
    assert info["instruction"] == env.get_wrapper_attr("task_description")
    assert info["seed"] == 5 and info["is_success"] is False
    # What LeRobot's eval loop reads through the wrappers gymnasium.make adds.
    assert env.get_wrapper_attr("_max_episode_steps") == {t["id"]: t for t in autobio.tasks()}[task]["max_steps"]
    env.close()


def replay(env, seed, actions):
    obs, info = env.reset(seed=seed)
    for k, a in enumerate(actions):
        obs, reward, terminated, truncated, info = env.step(a)
        if terminated or truncated:
            assert k == len(actions) - 1, f"ended at step {k + 1} of {len(actions)}"
    return reward, terminated, truncated, info


@pytest.mark.parametrize("task", ["thermal_cycler.close_lid", "tube.transfer"])
def test_the_experts_recorded_actions_give_evals_episode(expert_runs, task):
    folder, results = expert_runs
    env = autobio.make(task)
    for episode in results[task]["episodes"]:
        rec = autobio.load_recording(folder / f"{task}_seed{episode['seed']}.mcap")
        assert rec.seed == episode["seed"] and rec.task_id == task
        assert rec.actions.shape == (episode["control_steps"], len(env.action_names))
        reward, terminated, truncated, info = replay(env, episode["seed"], rec.actions)
        assert episode["success"] and terminated and not truncated
        assert reward == pytest.approx(episode["verdict"]["score"]) and reward == 1.0
        assert info["is_success"] is True
        assert info["trajectory_hash"] == episode["trajectory_hash"]
        assert info["control_steps"] == episode["control_steps"]
    # Another seed's actions on this seed: a different episode (the lid may still end up shut:
    # the thermal cycler's seeds draw only the arm's start).
    first, second = results[task]["episodes"]
    rec = autobio.load_recording(folder / f"{task}_seed{second['seed']}.mcap")
    _, terminated, _, info = replay_until_done(env, first["seed"], rec.actions)
    assert info["trajectory_hash"] != first["trajectory_hash"]


def test_a_two_robot_episode_replays_to_evals_hash(tmp_path):
    """Both arms' recorded actions (each robot's block in task order) stepped through the Python
    env give the episode `autobio eval` ran: its hash, length and success."""
    task = "tube.screw_cap"
    run_autobio("eval", "--protocol", "protocols/tube/screw_cap.toml", "--episodes", 1,
                "--seed", 0, "--out", tmp_path, "--record")
    episode = json.loads((tmp_path / f"{task}.results.json").read_text())["episodes"][0]
    rec = autobio.load_recording(tmp_path / f"{task}_seed0.mcap")
    env = autobio.make(task, image_size=(32, 32))
    assert len(rec.robots) == 2 and rec.task_id == task
    assert rec.actions.shape == (episode["control_steps"], len(env.action_names))
    reward, terminated, truncated, info = replay(env, 0, rec.actions)
    assert episode["success"] and terminated and not truncated and reward == 1.0
    assert info["trajectory_hash"] == episode["trajectory_hash"] == rec.trajectory_hash
    assert info["control_steps"] == episode["control_steps"]
    # The second arm's action at step 40 nudged by 1e-9: another trajectory.
    nudged = rec.actions.copy()
    nudged[40, rec.actions.shape[1] // 2] += 1e-9  # its first joint (both are Aloha arms)
    _, _, _, info = replay_until_done(env, 0, nudged)
    assert info["trajectory_hash"] != episode["trajectory_hash"]


def replay_until_done(env, seed, actions):
    env.reset(seed=seed)
    out = None
    for a in actions:
        out = env.step(a)
        if out[2] or out[3]:
            break
    return out[1], out[2], out[3], out[4]


def test_random_actions_end_truncated_with_reward_zero():
    env = gymnasium.make("autobio/centrifuge_5430.close_lid-v0", image_size=(32, 32))
    env.action_space.seed(7)
    obs, info = env.reset(seed=1)
    steps, done = 0, False
    while not done:
        obs, reward, terminated, truncated, info = env.step(env.action_space.sample())
        steps += 1
        done = terminated or truncated
        if not done:
            assert reward == 0.0
    assert truncated and not terminated and reward == 0.0 and not info["is_success"]
    assert steps <= env.get_wrapper_attr("_max_episode_steps")
    assert info["time"] == pytest.approx(env.unwrapped._core.time_limit_s, abs=0.021)


def test_the_same_seed_and_actions_give_the_same_episode_and_seeds_differ():
    env = autobio.make("thermal_cycler.open_lid", image_size=(32, 32))
    rng = np.random.default_rng(3)
    actions = [env.action_space.low + (env.action_space.high - env.action_space.low) * 0.5
               + rng.normal(0, 0.01, env.action_space.shape) for _ in range(30)]
    a = replay_until_done(env, 11, actions)[3]
    b = replay_until_done(env, 11, actions)[3]
    c = replay_until_done(env, 12, actions)[3]
    assert a["trajectory_hash"] == b["trajectory_hash"] != c["trajectory_hash"]
    # reset() without a seed goes on to the next one.
    env.reset(seed=40)
    _, info = env.reset()
    assert info["seed"] == 41


@pytest.mark.parametrize("task", SHIPPED)
def test_the_instruction_can_be_observed_on_every_task(task):
    env = autobio.make(task, image_size=(16, 16), instruction_in_obs=True)
    for seed in range(3):
        obs, info = env.reset(seed=seed)
        assert env.observation_space.contains(obs), obs["instruction"]
        assert obs["instruction"] == info["instruction"]


def test_observation_matches_the_layouts_and_the_instruction_can_be_observed():
    env = autobio.make("tube.transfer", image_size=(32, 32), instruction_in_obs=True)
    obs, info = env.reset(seed=2)
    assert env.observation_space.contains(obs)
    assert obs["instruction"] == info["instruction"] and "tube" in obs["instruction"]
    assert env.state_names[0].startswith("arm/") and env.action_names[-1].startswith("arm/gripper")
    frame = env.render()
    assert frame.shape == (32, 32 * len(env.camera_names), 3)


def test_bad_actions_and_protocols_raise_clear_errors(tmp_path):
    env = autobio.make("thermal_cycler.close_lid", image_size=(32, 32))
    with pytest.raises(gymnasium.error.ResetNeeded):
        env.step(env.action_space.sample())
    env.reset(seed=0)
    with pytest.raises(ValueError, match="action has 3 values, the robots take 7"):
        env.step([0.0, 0.0, 0.0])
    wild = env.action_space.high.copy()
    wild[0] = 100.0
    with pytest.raises(ValueError, match="outside its actuator's range"):
        env.step(wild)
    wild[0] = np.nan
    with pytest.raises(ValueError, match="not a finite number"):
        env.step(wild)
    # Refused actions moved nothing: the episode goes on from where it was.
    assert env.unwrapped._core.control_steps == 0
    info = env.step(env.action_space.sample())[4]
    assert info["control_steps"] == 1
    with pytest.raises(autobio.ProtocolError, match="neither a shipped task id"):
        autobio.make("thermal_cycler.close_lids")
    bad = tmp_path / "bad.toml"
    text = (autobio_root() / "protocols/thermal_cycler/close_lid.toml").read_text()
    bad.write_text(text.replace('kind = "thermal_cycler"', 'kind = "thermal_cycle"'))
    with pytest.raises(autobio.ProtocolError) as e:
        autobio.make(str(bad))
    message = str(e.value)
    assert f"{bad}:" in message and "error[E" in message and "thermal_cycler" in message, message


def test_a_protocol_file_runs_like_its_shipped_id():
    by_file = autobio.make(str(autobio_root() / "protocols/thermal_cycler/close_lid.toml"))
    by_id = autobio.make("thermal_cycler.close_lid")
    assert json.loads(by_file._core.task_json())["id"] == by_id.task_id
    a = by_file.reset(seed=9)[0]["agent_pos"]
    b = by_id.reset(seed=9)[0]["agent_pos"]
    assert np.array_equal(a, b)


def autobio_root():
    from conftest import ROOT

    return ROOT
