"""A server on vla-eval's wire (its own `pack_message`/`unpack_message`) that greets the client and
then never answers an observation: it sends an `error` frame for another frame's seq every 0.5 s
instead, for a minute. A client that restarts its reply timeout on every frame it reads waits the
whole minute; one with a deadline per reply gives up at its timeout.

`--events FILE` appends one JSON line per `error` frame sent (with its time since the observation
came), so a test sees the noise was made.

Prints `listening on ws://HOST:PORT` once ready (port 0 picks a free one)."""

import argparse
import asyncio
import functools
import json
import time

from vla_eval.protocol.messages import Message, MessageType, pack_message, unpack_message
from websockets.asyncio.server import serve


def event(path, **fields):
    if path:
        with open(path, "a") as log:
            log.write(json.dumps(fields) + "\n")


async def handler(ws, events=None):
    async for raw in ws:
        msg = unpack_message(raw)
        if msg.type == MessageType.HELLO:
            await ws.send(pack_message(Message(type=MessageType.HELLO, payload={"server": "noise"}, seq=msg.seq)))
        elif msg.type == MessageType.OBSERVATION:
            start = time.monotonic()
            for _ in range(120):
                error = {"error": "an error for an earlier frame (noise on request)"}
                await ws.send(pack_message(Message(type=MessageType.ERROR, payload=error, seq=0)))
                event(events, event="error_frame", after_s=time.monotonic() - start)
                await asyncio.sleep(0.5)


async def main():
    p = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    p.add_argument("--host", default="127.0.0.1")
    p.add_argument("--port", type=int, default=0)
    p.add_argument("--events", help="append each error frame sent here (JSON lines)")
    args = p.parse_args()
    async with serve(functools.partial(handler, events=args.events), args.host, args.port, compression=None, max_size=None) as server:
        port = server.sockets[0].getsockname()[1]
        print(f"listening on ws://{args.host}:{port}", flush=True)
        await asyncio.Future()


if __name__ == "__main__":
    asyncio.run(main())
