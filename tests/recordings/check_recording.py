"""Reads an autobio recording with the mcap library's own protobuf decoder (as Foxglove's tools
decode a channel from its schema) and prints what it found as one JSON object: per topic the
schema name, encodings and message count; per camera the image format, PNG size and count; the
physics state's spec and length."""
import json
import struct
import sys

from mcap.reader import make_reader
from mcap_protobuf.decoder import DecoderFactory

out = {"topics": {}, "cameras": {}, "state": None}
with open(sys.argv[1], "rb") as f:
    reader = make_reader(f)
    protobuf = DecoderFactory()
    decoders = {}
    for schema, channel, message in reader.iter_messages(log_time_order=True):
        t = out["topics"].setdefault(
            channel.topic,
            {
                "schema": schema.name if schema else None,
                "schema_encoding": schema.encoding if schema else None,
                "message_encoding": channel.message_encoding,
                "count": 0,
            },
        )
        t["count"] += 1
        if channel.message_encoding != "protobuf":
            json.loads(message.data)
            continue
        if schema.id not in decoders:
            decoders[schema.id] = protobuf.decoder_for(channel.message_encoding, schema)
        decoded = decoders[schema.id](message.data)
        if schema.name == "foxglove.CompressedImage":
            data = decoded.data
            assert data[:8] == b"\x89PNG\r\n\x1a\n", "not a PNG"
            width, height = struct.unpack(">II", data[16:24])
            stamp = decoded.timestamp.seconds * 10**9 + decoded.timestamp.nanos
            assert stamp == message.log_time, (stamp, message.log_time)
            c = out["cameras"].setdefault(
                channel.topic,
                {"format": decoded.format, "frame_id": decoded.frame_id, "sizes": [], "count": 0},
            )
            if [width, height] not in c["sizes"]:
                c["sizes"].append([width, height])
            c["count"] += 1
        elif schema.name == "autobio.PhysicsState":
            s = out["state"] or {"spec": decoded.spec, "lengths": [], "count": 0}
            if len(decoded.state) not in s["lengths"]:
                s["lengths"].append(len(decoded.state))
            s["count"] += 1
            out["state"] = s
print(json.dumps(out, sort_keys=True))
