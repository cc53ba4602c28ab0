"""A model server built on the `vla-eval` package (allenai's evaluation harness, 0.8.0): its
`PredictModelServer` and `serve_async`, unchanged, answering each observation with the scripted
expert's recorded action for that step (see expert_actions.py). The episode is named by the
`task` the client sends in `episode_start`. It checks each observation's images, state and task
description, so a client that sends the wrong thing gets an `error` frame.

`--log FILE` records each `episode_start`'s session, so a test can see connections kept;
`--fail-start-seed S` raises in `on_episode_start` for seed S (vla-eval answers an `error` frame);
`--duplicate-seed S` answers the third observation of seed S's episode twice (through the package's
own `send_action`, so the second copy carries that observation's seq and is read as the reply to
the next one: a stale reply).

Prints `listening on ws://HOST:PORT` once ready (port 0 picks a free one)."""

import argparse
import json

import anyio
import numpy as np
from vla_eval.model_servers.predict import PredictModelServer
from vla_eval.model_servers.serve import serve_async
from vla_eval.specs import GRIPPER_RAW, DimSpec

from expert_actions import Library


class ExpertServer(PredictModelServer):
    def __init__(self, library, log=None, fail_start_seed=None, duplicate_seed=None):
        super().__init__(chunk_size=None)
        self.duplicate_seed = duplicate_seed
        self.seeds = {}
        self.observations = {}
        self.library = library
        self.episodes = {}
        self.log = log
        self.fail_start_seed = fail_start_seed

    def get_action_spec(self):
        return {"joints": DimSpec("joints", 6, "absolute_joint_positions"), "gripper": GRIPPER_RAW}

    def get_observation_spec(self):
        return {"state": DimSpec("state", 7, "joint_positions")}

    async def on_episode_start(self, config, ctx):
        task = config["task"]
        if self.log:
            with open(self.log, "a") as log:
                log.write(json.dumps({"session": ctx.session_id, "seed": task["seed"]}) + "\n")
        if task["seed"] == self.fail_start_seed:
            raise RuntimeError(f"no checkpoint for seed {task['seed']} (a fault on request)")
        self.episodes[ctx.session_id] = self.library.episode(task["id"], task["seed"])
        self.seeds[ctx.session_id] = task["seed"]
        self.observations[ctx.session_id] = 0
        await super().on_episode_start(config, ctx)

    async def on_observation(self, obs, ctx):
        await super().on_observation(obs, ctx)
        self.observations[ctx.session_id] += 1
        if self.seeds.get(ctx.session_id) == self.duplicate_seed and self.observations[ctx.session_id] == 3:
            episode = self.episodes[ctx.session_id]
            await ctx.send_action({"actions": np.asarray(episode.chunk(0, 1)[0], dtype=np.float64)})

    def predict(self, obs, ctx):
        episode = self.episodes[ctx.session_id]
        images = obs["images"]
        assert len(images) >= 2, f"{len(images)} images"
        for name, img in images.items():
            if img is None:
                continue
            assert isinstance(img, np.ndarray) and img.dtype == np.uint8, f"{name}: {type(img)}"
            assert img.shape == (224, 224, 3), f"{name}: {img.shape}"
        state = obs["states"]
        assert state.shape == (len(episode.actions[0]),), f"state {state.shape}"
        allowed = [episode.instruction, *episode.stage_instructions]
        assert obs["task_description"] in allowed, obs["task_description"]
        return {"actions": np.asarray(episode.chunk(ctx.step, 1)[0], dtype=np.float64)}


async def main(args):
    server = ExpertServer(Library(args.recordings), args.log, args.fail_start_seed, args.duplicate_seed)
    async with anyio.create_task_group() as tg:
        port = await tg.start(serve_async, server, args.host, args.port)
        print(f"listening on ws://{args.host}:{port}", flush=True)


if __name__ == "__main__":
    p = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    p.add_argument("--recordings", required=True)
    p.add_argument("--host", default="127.0.0.1")
    p.add_argument("--port", type=int, default=0)
    p.add_argument("--log", help="append each episode_start's session id and seed here (JSON lines)")
    p.add_argument("--fail-start-seed", type=int, help="raise in on_episode_start for this seed")
    p.add_argument("--duplicate-seed", type=int, help="answer this seed's third observation twice")
    anyio.run(main, p.parse_args())
