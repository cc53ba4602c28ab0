"""What LeRobot's own eval loop (lerobot 0.4's `lerobot_eval.py` and `envs/utils.py`) does with a
gym environment, done here with gymnasium's real SyncVectorEnv: `gym.make(...,
disable_env_checker=True)` inside a SAME_STEP-autoreset vector env, `call("_max_episode_steps")`,
`call("task_description")`, the `pixels/<camera>` and `agent_pos` observation it preprocesses,
and `info["final_info"]["is_success"]` when an episode ends."""

import gymnasium as gym
import numpy as np
from gymnasium.vector import AutoresetMode, SyncVectorEnv

import autobio


def preprocess_like_lerobot(obs):
    """LeRobot's `preprocess_observation` checks, without torch: uint8 channel-last images under
    `pixels`, keys usable as `observation.images.<camera>`, float state from `agent_pos`."""
    out = {}
    for camera, img in obs["pixels"].items():
        assert "/" not in camera
        _b, h, w, c = img.shape
        assert c < h and c < w and img.dtype == np.uint8, (camera, img.shape, img.dtype)
        out[f"observation.images.{camera}"] = img.transpose(0, 3, 1, 2).astype(np.float32) / 255
    out["observation.state"] = obs["agent_pos"].astype(np.float32)
    return out


def test_lerobots_eval_loop_reads_what_it_needs(expert_runs):
    folder, results = expert_runs
    task = "tube.transfer"
    rec = autobio.load_recording(folder / f"{task}_seed0.mcap")
    make = lambda: gym.make(f"autobio/{task}-v0", disable_env_checker=True, image_size=(32, 32))
    env = SyncVectorEnv([make], autoreset_mode=AutoresetMode.SAME_STEP)
    assert env.call("_max_episode_steps") == (autobio.AutobioEnv(task)._max_episode_steps,)
    obs, info = env.reset(seed=0)
    (description,) = env.call("task_description")
    assert description == info["instruction"][0] and "tube" in description
    batch = preprocess_like_lerobot(obs)
    assert batch["observation.state"].shape == (1, 7)
    assert set(batch) == {"observation.images.table_front", "observation.images.arm_wrist",
                          "observation.state"}
    for k, a in enumerate(rec.actions):
        obs, reward, terminated, truncated, info = env.step(a[None])
        if terminated[0] or truncated[0]:
            break
    assert k == len(rec.actions) - 1 and terminated[0] and reward[0] == 1.0
    assert bool(info["final_info"]["is_success"][0]) is True
    env.close()
