"""The vector environment: N episodes on Rust threads are the single environment's episodes,
autoreset follows gymnasium's NEXT_STEP mode, and gymnasium.make_vec reaches it."""

import gymnasium
import numpy as np
import pytest
from gymnasium.vector import AutoresetMode

import autobio


def single_hashes(task, seeds, actions):
    env = autobio.make(task, image_size=(32, 32))
    out = []
    for i, seed in enumerate(seeds):
        env.reset(seed=seed)
        for a in actions[i]:
            info = env.step(a)[4]
        out.append(info["trajectory_hash"])
    return out


def test_vector_episodes_are_the_single_environments(expert_runs):
    folder, results = expert_runs
    task = "thermal_cycler.close_lid"
    recs = [autobio.load_recording(folder / f"{task}_seed{s}.mcap") for s in (0, 1)]
    venv = gymnasium.make_vec(
        f"autobio/{task}-v0", num_envs=2, vectorization_mode="vector_entry_point",
        image_size=(32, 32),
    )
    assert isinstance(venv, autobio.AutobioVectorEnv)
    assert venv.metadata["autoreset_mode"] == AutoresetMode.NEXT_STEP
    obs, infos = venv.reset(seed=0)
    assert list(infos["seed"]) == [0, 1]
    assert obs["pixels"]["table_front"].shape == (2, 32, 32, 3)
    assert obs["agent_pos"].shape == (2, 7)
    longest = max(len(r.actions) for r in recs)
    done_at = [None, None]
    hashes = [None, None]
    for k in range(longest):
        actions = np.stack([r.actions[min(k, len(r.actions) - 1)] for r in recs])
        obs, rewards, terminated, truncated, infos = venv.step(actions)
        for i in range(2):
            if done_at[i] is None and (terminated[i] or truncated[i]):
                done_at[i] = k + 1
                hashes[i] = infos["trajectory_hash"][i]
                assert terminated[i] and rewards[i] == 1.0 and infos["is_success"][i]
    want = {e["seed"]: e for e in results[task]["episodes"]}
    for i in range(2):
        assert done_at[i] == want[i]["control_steps"]
        assert hashes[i] == want[i]["trajectory_hash"]
    venv.close()


def test_random_batches_match_single_envs_and_a_bad_action_moves_no_slot():
    task = "tube.transfer"
    venv = autobio.make_vec(task, num_envs=3, image_size=(32, 32))
    venv.action_space.seed(4)
    venv.reset(seed=10)
    actions = [venv.action_space.sample() for _ in range(12)]
    for a in actions:
        obs, rewards, terminated, truncated, infos = venv.step(a)
    per_env = [[a[i] for a in actions] for i in range(3)]
    assert list(infos["trajectory_hash"]) == single_hashes(task, [10, 11, 12], per_env)
    assert list(infos["control_steps"]) == [12, 12, 12]
    bad = venv.action_space.sample()
    bad[2][0] = 100.0
    with pytest.raises(ValueError, match="environment 2: .*outside its actuator's range"):
        venv.step(bad)
    obs, rewards, terminated, truncated, infos = venv.step(venv.action_space.sample())
    assert list(infos["control_steps"]) == [13, 13, 13]
    obs, infos = venv.reset(seed=np.int64(3))
    assert list(infos["seed"]) == [3, 4, 5]
    venv.close()


def test_an_ended_episode_is_reset_on_the_next_step_with_its_next_seed(expert_runs):
    folder, results = expert_runs
    task = "tube.transfer"
    rec = autobio.load_recording(folder / f"{task}_seed0.mcap")
    venv = autobio.make_vec(task, num_envs=2, image_size=(32, 32))
    venv.reset(seed=[0, 5])
    hold = venv.action_space.sample()[1]
    for k, a in enumerate(rec.actions):
        obs, rewards, terminated, truncated, infos = venv.step(np.stack([a, hold]))
    assert terminated[0] and rewards[0] == 1.0
    # NEXT_STEP: this step's action is ignored for slot 0, which starts seed 0 + num_envs.
    obs, rewards, terminated, truncated, infos = venv.step(np.stack([rec.actions[0], hold]))
    assert infos["seed"][0] == 2 and infos["control_steps"][0] == 0
    assert rewards[0] == 0.0 and not terminated[0] and not truncated[0]
    assert infos["seed"][1] == 5 and infos["control_steps"][1] == len(rec.actions) + 1
    venv.close()
