"""The environment state as an observation (gym-pusht's ``environment_state_agent_pos``, LeRobot's
``observation.environment_state``), and the conventions a new user trips on: ``image_size`` as
an int, ``reset``/``step`` docstrings, vla-eval's action and observation specs."""

import gymnasium
import numpy as np
import pytest
from gymnasium.utils.env_checker import check_env
from vla_eval.specs import check_specs, IMAGE_RGB, LANGUAGE, RAW

import autobio
from autobio.benchmark import AutobioBenchmark

TASK = "thermal_cycler.close_lid"


def test_image_size_takes_an_int_everywhere():
    env = autobio.make(TASK, image_size=32)
    obs, _ = env.reset(seed=0)
    assert {img.shape for img in obs["pixels"].values()} == {(32, 32, 3)}
    env.close()
    env = gymnasium.make(f"autobio/{TASK}-v0", image_size=24, disable_env_checker=True)
    obs, _ = env.reset(seed=0)
    assert {img.shape for img in obs["pixels"].values()} == {(24, 24, 3)}
    env.close()
    vec = autobio.make_vec(TASK, 2, image_size=16)
    obs, _ = vec.reset(seed=0)
    assert {img.shape for img in obs["pixels"].values()} == {(2, 16, 16, 3)}
    vec.close()
    # A pair is (width, height); anything else is a clear error.
    env = autobio.make(TASK, image_size=(40, 20))
    obs, _ = env.reset(seed=0)
    assert {img.shape for img in obs["pixels"].values()} == {(20, 40, 3)}
    with pytest.raises(TypeError, match="image_size"):
        autobio.make(TASK, image_size="big")
    with pytest.raises(ValueError, match="image_size"):
        autobio.make(TASK, image_size=(1, 2, 3))
    with pytest.raises(ValueError, match="image_size"):
        autobio.make(TASK, image_size=0)


def test_reset_and_step_carry_their_own_docstrings():
    for method in (autobio.AutobioEnv.reset, autobio.AutobioEnv.step):
        doc = method.__doc__ or ""
        assert "autobio" in doc or "action_names" in doc, method
        assert doc != getattr(gymnasium.Env, method.__name__).__doc__


def test_the_environment_state_is_observed_in_the_tasks_layout(expert_runs):
    folder, _ = expert_runs
    names = next(t for t in autobio.tasks() if t["id"] == TASK)["environment_state_names"]
    assert names[:7] == ["cycler.x", "cycler.y", "cycler.z", "cycler.qw", "cycler.qx", "cycler.qy",
                         "cycler.qz"]
    assert "cycler.lid" in names
    env = autobio.make(TASK, obs_type="environment_state_agent_pos")
    assert env.environment_state_names == names
    assert set(env.observation_space.spaces) == {"environment_state", "agent_pos"}
    obs, _ = env.reset(seed=0)
    assert set(obs) == {"environment_state", "agent_pos"}
    assert obs["environment_state"].shape == (len(names),)
    assert env.observation_space.contains(obs)
    lid = names.index("cycler.lid")
    start = obs["environment_state"][lid]
    rec = autobio.load_recording(folder / f"{TASK}_seed0.mcap")
    for a in rec.actions:
        obs, _, terminated, truncated, _ = env.step(a)
        if terminated or truncated:
            break
    assert terminated
    # The expert closed the lid: the state shows it; the cycler itself did not move.
    assert abs(obs["environment_state"][lid] - start) > 0.5, (start, obs["environment_state"][lid])
    again = autobio.make(TASK, obs_type="environment_state_agent_pos")
    first, _ = again.reset(seed=0)
    np.testing.assert_array_equal(first["environment_state"][:7], obs["environment_state"][:7])
    # Another seed draws another layout of values, never another layout of names.
    other, _ = again.reset(seed=1)
    assert other["environment_state"].shape == first["environment_state"].shape


def test_the_state_observation_types_pass_gymnasiums_checker_and_draw_no_camera():
    env = autobio.make(TASK, obs_type="environment_state_agent_pos")
    check_env(env, skip_render_check=True)
    both = autobio.make(TASK, image_size=16, obs_type="pixels_environment_state_agent_pos")
    obs, _ = both.reset(seed=3)
    assert set(obs) == {"pixels", "environment_state", "agent_pos"}
    with pytest.raises(ValueError, match="obs_type"):
        autobio.make(TASK, obs_type="state")
    vec = autobio.make_vec(TASK, 2, obs_type="environment_state_agent_pos")
    obs, _ = vec.reset(seed=0)
    assert set(obs) == {"environment_state", "agent_pos"}
    assert obs["environment_state"].shape == (2, len(env.environment_state_names))
    vec.close()


def test_the_vla_eval_benchmark_declares_its_specs_and_a_matching_server_gets_no_warning():
    bench = AutobioBenchmark(tasks=[TASK], seeds=[0], image_size=32)
    action = bench.get_action_spec()["actions"]
    assert action.dims == 7 and action.format == "autobio_joint_targets"
    obs = bench.get_observation_spec()
    assert set(obs) == {"image", "state", "language"}
    assert obs["state"].dims == 7 and obs["image"].format == IMAGE_RGB.format
    # What vla-eval's own pi0 and LeRobot servers declare: raw actions (accepted as autobio's
    # layout), images and language: no warning.
    server_obs = {"image": IMAGE_RGB, "language": LANGUAGE}
    assert check_specs({"actions": RAW}, bench.get_action_spec(), server_obs, obs) == []
    # A server that wants what the benchmark does not send, or in another format, is warned
    # about before the first episode.
    wants_more = dict(server_obs, wrist_image=IMAGE_RGB, state=RAW)
    assert sorted(check_specs({"actions": RAW}, bench.get_action_spec(), wants_more, obs)) == [
        "observation [state]: state: joint_positions vs raw",
        "observation [wrist_image]: server expects it but benchmark doesn't provide it",
    ]
    with_state = AutobioBenchmark(tasks=[TASK], seeds=[0], image_size=32, environment_state=True)
    spec = with_state.get_observation_spec()["environment_state"]
    names = next(t for t in autobio.tasks() if t["id"] == TASK)["environment_state_names"]
    assert spec.dims == len(names)
    raw = with_state.reset(with_state.get_tasks()[0])
    made = with_state.make_obs(raw, with_state.get_tasks()[0])
    assert made["environment_state"].shape == (len(names),)
    with_state.cleanup()


def test_out_of_range_actions_are_refused_unless_the_env_clips():
    # autobio refuses an action outside an actuator's range; `clip_actions=True` (what the
    # `autobio` env type for lerobot-eval sets) clips a finite one instead, as ClipAction does.
    env = autobio.make("thermal_cycler.close_lid", seed=0, image_size=8,
                       obs_type="environment_state_agent_pos")
    action = env.unwrapped._core.hold_action()
    over = np.asarray(action, dtype=np.float64)
    over[-1] = env.action_space.high[-1] + 0.5
    with pytest.raises(ValueError, match="outside its actuator's range"):
        env.step(over)
    clipped = autobio.make("thermal_cycler.close_lid", seed=0, image_size=8,
                           obs_type="environment_state_agent_pos", clip_actions=True)
    inside = over.copy()
    inside[-1] = env.action_space.high[-1]
    a = clipped.step(over)[0]
    b = env.step(inside)[0]
    assert np.array_equal(a["agent_pos"], b["agent_pos"])
    assert clipped.unwrapped.trajectory_hash == env.unwrapped.trajectory_hash
    over[0] = np.nan
    with pytest.raises(ValueError):
        clipped.step(over)
