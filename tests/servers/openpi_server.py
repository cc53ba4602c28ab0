"""A model server speaking openpi's websocket protocol, built on the `openpi-client` package's own
msgpack-numpy, that answers with the scripted expert's recorded actions (see expert_actions.py).

It behaves like openpi's `WebsocketPolicyServer`: a metadata frame on connect (unless
`--no-metadata`, AutoBio's variant), strictly alternating request and reply, errors as a text
frame with the traceback followed by close code 1011. It checks the observation it gets against
the pi0 layout and the recorded instruction, so a client that sends the wrong thing fails.

`--fault MODE` misbehaves on query `--fault-at` of episode `--fault-episode` (counted by the
`{"reset": true}` frames the client sends), for the fault tests:
  close    closes the connection instead of answering
  stall    never answers
  shape    answers actions one component too long
  nan      answers a NaN action
  range    answers an arm target of 100 rad
  error    raises, so the client gets a text frame and close 1011
  garbage  answers bytes that are not msgpack
  trickle  sends its reply in 16-byte fragments 0.05 s apart (seconds for the whole reply, each
           fragment well inside any timeout)
  long     answers one action more than `--chunk`
  close-after / abort-after
           after the last reply of episode `--fault-episode` (the chunk holding its last recorded
           action), closes the connection with a close frame / drops it with no close frame, so
           the client holds a stale connection when the next episode starts

`--layout rdt` expects RDT's layout (a 128-d state, each camera's frame and an earlier one) and
answers 128-d actions.

`--log FILE` appends each query's task, seed, prompt, connection number and observation keys
(with the environment state where one was sent), so a test can see the
instruction switch between a chain's stages and count connections. `--events FILE` appends what
the server did on its own (each keepalive ping sent, the metadata frame sent) with its time since
the connection opened, so a test sees an injected behaviour happen.

Prints `listening on ws://HOST:PORT` once ready (port 0 picks a free one)."""

import argparse
import asyncio
import json
import math
import sys
import time
import traceback

import numpy as np
import websockets
from websockets.asyncio.server import serve
from openpi_client import msgpack_numpy

from expert_actions import Library


# RDT's 128-d unified vector: where a single arm's 6 joints and gripper sit.
RDT_INDICES = [0, 1, 2, 3, 4, 5, 10]


def check_image(obs, key):
    img = obs[key]
    assert isinstance(img, np.ndarray), f"{key} is {type(img)}"
    assert img.dtype == np.uint8 and img.shape == (224, 224, 3), f"{key} {img.dtype} {img.shape}"
    assert img.std() > 1.0, f"{key} is blank"
    return img


def check_observation(obs, episode, args):
    """Checks the observation's layout; returns whether the earlier frames (RDT) differ from the
    current ones."""
    state = obs["observation/state"]
    assert isinstance(state, np.ndarray) and state.dtype == np.float32, f"state {type(state)}"
    width = len(episode.actions[0])
    if args.layout == "rdt":
        assert state.shape == (128,), f"state shape {state.shape}"
        others = np.delete(state, RDT_INDICES[:width])
        assert not others.any(), "state components outside the arm's slots"
    else:
        assert state.shape == (width,), f"state shape {state.shape}"
    moved = False
    for key in ("observation/image", "observation/wrist_image"):
        now = check_image(obs, key)
        if args.layout == "rdt":
            before = check_image(obs, key.replace("observation/", "observation/-1/"))
            moved |= bool((before != now).any())
    assert "observation/wrist_image_2" in obs, "no observation/wrist_image_2 key"
    prompt = obs["prompt"]
    allowed = [episode.instruction, *episode.stage_instructions]
    assert prompt in allowed, f"prompt {prompt!r} is not the episode's instruction"
    return moved


async def trickle(data):
    """The reply as 16-byte fragments of one message, 0.05 s apart."""
    for i in range(0, len(data), 16):
        yield data[i:i + 16]
        await asyncio.sleep(0.05)


def event(args, opened, **fields):
    """One line of what the server did on its own (`--events`)."""
    if args.events:
        with open(args.events, "a") as log:
            log.write(json.dumps({**fields, "after_s": time.monotonic() - opened}) + "\n")


async def keepalive(ws, args, opened):
    """websockets' keepalive, done here so that each ping is logged: one every interval."""
    while True:
        await asyncio.sleep(args.ping_interval)
        try:
            await ws.ping()
        except websockets.ConnectionClosed:
            return
        event(args, opened, event="ping")


async def handler(ws, library, args, counters):
    counters["connections"] += 1
    connection = counters["connections"]
    opened = time.monotonic()
    pinger = asyncio.ensure_future(keepalive(ws, args, opened))
    try:
        await serve_connection(ws, library, args, counters, connection, opened)
    finally:
        pinger.cancel()


async def serve_connection(ws, library, args, counters, connection, opened):
    packer = msgpack_numpy.Packer()
    if args.metadata_delay:
        await asyncio.sleep(args.metadata_delay)
    if not args.no_metadata:
        await ws.send(packer.pack({"server": "autobio reference openpi expert", "action_horizon": args.chunk}))
        event(args, opened, event="metadata")
    episode = None
    query = 0
    try:
        async for message in ws:
            try:
                obs = msgpack_numpy.unpackb(message)
                if obs.get("reset"):
                    task = obs["task"]
                    episode = library.episode(task["id"], task["seed"])
                    counters["episodes"] += 1
                    query = 0
                    continue
                if episode is None:
                    raise RuntimeError("an observation before any reset frame: which episode is this?")
                moved = check_observation(obs, episode, args)
                if args.log:
                    with open(args.log, "a") as log:
                        line = {"task": task["id"], "seed": task["seed"], "query": query, "prompt": obs["prompt"],
                                "history_differs": moved, "connection": connection,
                                "keys": sorted(str(k) for k in obs)}
                        if "observation.environment_state" in obs:
                            env = np.asarray(obs["observation.environment_state"])
                            line["environment_state"] = [float(x) for x in env.reshape(-1)]
                        log.write(json.dumps(line) + "\n")
                chunk = np.asarray(episode.chunk(query * args.execute, args.chunk), dtype=np.float64)
                if args.layout == "rdt":
                    wide = np.zeros((chunk.shape[0], 128))
                    wide[:, RDT_INDICES[: chunk.shape[1]]] = chunk
                    chunk = wide
                in_fault_episode = counters["episodes"] - 1 == args.fault_episode
                faulty = args.fault and in_fault_episode and query == args.fault_at
                last_reply = query * args.execute + args.chunk >= len(episode.actions)
                query += 1
                if args.fault in ("close-after", "abort-after") and in_fault_episode and last_reply:
                    await ws.send(packer.pack({"actions": chunk}))
                    if args.fault == "close-after":
                        await ws.close(1001, "idle")
                    else:
                        ws.transport.abort()
                    return
                if faulty:
                    if args.fault == "close":
                        await ws.close()
                        return
                    if args.fault == "stall":
                        await asyncio.sleep(3600)
                    if args.fault == "shape":
                        chunk = np.concatenate([chunk, np.zeros((chunk.shape[0], 1))], axis=1)
                    if args.fault == "nan":
                        chunk[0, 0] = math.nan
                    if args.fault == "range":
                        chunk[0, 1] = 100.0
                    if args.fault == "error":
                        raise RuntimeError("the model ran out of memory (a fault on request)")
                    if args.fault == "garbage":
                        await ws.send(b"\xc1 this is not msgpack")
                        continue
                    if args.fault == "long":
                        chunk = np.concatenate([chunk, chunk[-1:]], axis=0)
                    if args.fault == "trickle":
                        await ws.send(trickle(packer.pack({"actions": chunk})))
                        continue
                await ws.send(packer.pack({"actions": chunk, "server_timing": {"infer_ms": 0.0}}))
            except Exception:
                await ws.send(traceback.format_exc())
                await ws.close(code=1011, reason="internal error")
                return
    except websockets.exceptions.ConnectionClosed:
        pass


async def main():
    p = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    p.add_argument("--recordings", required=True)
    p.add_argument("--host", default="127.0.0.1")
    p.add_argument("--port", type=int, default=0)
    p.add_argument("--chunk", type=int, default=50)
    p.add_argument("--execute", type=int, default=50, help="actions the client runs of each chunk")
    p.add_argument("--no-metadata", action="store_true")
    p.add_argument("--metadata-delay", type=float, default=0.0,
                   help="seconds to wait before the metadata frame (a slow server)")
    p.add_argument("--ping-interval", type=float, default=20.0,
                   help="websocket keepalive pings (the websockets default: 20 s)")
    p.add_argument("--layout", choices=["pi0", "rdt"], default="pi0",
                   help="the observation and action layout to expect and answer in")
    p.add_argument("--fault", choices=["close", "stall", "shape", "nan", "range", "error", "garbage",
                                       "trickle", "long", "close-after", "abort-after"])
    p.add_argument("--fault-episode", type=int, default=1)
    p.add_argument("--fault-at", type=int, default=1)
    p.add_argument("--log", help="append each query's task, seed and prompt here (JSON lines)")
    p.add_argument("--events", help="append each ping and metadata frame sent here (JSON lines)")
    args = p.parse_args()
    library = Library(args.recordings)
    counters = {"episodes": 0, "connections": 0}
    async with serve(
        lambda ws: handler(ws, library, args, counters),
        args.host,
        args.port,
        compression=None,
        max_size=None,
        ping_interval=None,
    ) as server:
        port = server.sockets[0].getsockname()[1]
        print(f"listening on ws://{args.host}:{port}", flush=True)
        await asyncio.Future()


if __name__ == "__main__":
    sys.exit(asyncio.run(main()))
