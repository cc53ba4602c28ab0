"""Checks a LeRobot dataset autobio wrote with readers that are not ours: pyarrow for parquet
and metadata, ffprobe for videos. Asserts LeRobot's layout, schemas, row counts, indices,
timestamps, statistics' shapes and every frame's presentation time (1e-4 s), and prints a JSON
summary.

    python check_lerobot.py DATASET_DIR v2.1|v3.0"""

import json
import os
import subprocess
import sys

import pyarrow as pa
import pyarrow.parquet as pq

FPS = 50
TOL = 1e-4


def frames(path):
    """Every frame's presentation time (s) and the stream's codec and rate, by ffprobe."""
    out = subprocess.run(
        ["ffprobe", "-v", "error", "-select_streams", "v:0", "-show_entries",
         "stream=codec_name,avg_frame_rate,width,height,pix_fmt:frame=pts_time",
         "-of", "json", path],
        check=True, capture_output=True, text=True).stdout
    data = json.loads(out)
    stream = data["streams"][0]
    times = [float(f["pts_time"]) for f in data["frames"]]
    return stream, times


def check_rows(table, episodes, first_index):
    """Rows sorted by episode then frame; contiguous global index; timestamp = frame/fps."""
    cols = table.to_pydict()
    n = table.num_rows
    assert cols["index"] == list(range(first_index, first_index + n)), "index not contiguous"
    row = 0
    for ep, length in episodes:
        assert cols["episode_index"][row:row + length] == [ep] * length, f"episode {ep} rows"
        assert cols["frame_index"][row:row + length] == list(range(length)), f"episode {ep} frames"
        for i in range(length):
            assert abs(cols["timestamp"][row + i] - i / FPS) < TOL, f"timestamp {ep}/{i}"
        row += length
    assert row == n, f"{n} rows for {row} frames"


def check_schema(schema, state_dim, action_dim, env_dim=None):
    want = {
        "observation.state": pa.list_(pa.float32(), state_dim),
        "action": pa.list_(pa.float32(), action_dim),
        "timestamp": pa.float32(),
        "frame_index": pa.int64(),
        "episode_index": pa.int64(),
        "index": pa.int64(),
        "task_index": pa.int64(),
    }
    if env_dim is not None:
        want["observation.environment_state"] = pa.list_(pa.float32(), env_dim)
    for name, t in want.items():
        got = schema.field(name).type
        assert got.equals(t) or str(got).replace("element", "item") == str(t), f"{name}: {got} != {t}"
    hf = json.loads(schema.metadata[b"huggingface"])
    assert hf["info"]["features"]["observation.state"]["length"] == state_dim


def check_stats(stats, info, quantiles):
    for name, feat in info["features"].items():
        s = stats[name]
        for k in ["min", "max", "mean", "std", "count"] + (["q01", "q50", "q99"] if quantiles else []):
            assert k in s, f"stats of {name} lack {k}"
        if feat["dtype"] == "video":
            for k in ["min", "max", "mean", "std"]:
                v = s[k]
                assert len(v) == 3 and all(len(c) == 1 and len(c[0]) == 1 for c in v), f"{name}.{k} shape"
                assert all(0.0 <= c[0][0] <= 1.0 for c in v), f"{name}.{k} not in [0, 1]"
        else:
            assert len(s["mean"]) == feat["shape"][0], f"{name} mean shape"


def main(root, version):
    info = json.load(open(os.path.join(root, "meta/info.json")))
    assert info["codebase_version"] == version
    assert info["fps"] == FPS
    feats = info["features"]
    video_keys = [k for k, f in feats.items() if f["dtype"] == "video"]
    # A state dataset (`--observation state`) has the environment state and no camera.
    ed = None
    if "observation.environment_state" in feats:
        ed = feats["observation.environment_state"]["shape"][0]
        assert len(feats["observation.environment_state"]["names"]) == ed
    assert video_keys or ed, "neither camera nor environment-state features"
    for k in video_keys:
        assert feats[k]["names"] == ["height", "width", "channel"]
    sd, ad = feats["observation.state"]["shape"][0], feats["action"]["shape"][0]
    assert len(feats["observation.state"]["names"]) == sd
    summary = {"episodes": info["total_episodes"], "frames": info["total_frames"], "videos": {},
               "environment_state": ed}
    if version == "v2.1":
        episodes = [json.loads(l) for l in open(os.path.join(root, "meta/episodes.jsonl"))]
        tasks = [json.loads(l) for l in open(os.path.join(root, "meta/tasks.jsonl"))]
        ep_stats = [json.loads(l) for l in open(os.path.join(root, "meta/episodes_stats.jsonl"))]
        assert [e["episode_index"] for e in episodes] == list(range(len(episodes)))
        assert len(ep_stats) == len(episodes)
        first = 0
        for e in episodes:
            i, length = e["episode_index"], e["length"]
            path = os.path.join(root, info["data_path"].format(episode_chunk=i // 1000, episode_index=i))
            table = pq.read_table(path)
            check_schema(table.schema, sd, ad, ed)
            check_rows(table, [(i, length)], first)
            assert set(table.column("task_index").to_pylist()) <= {t["task_index"] for t in tasks}
            first += length
            for k in video_keys:
                v = os.path.join(root, info["video_path"].format(episode_chunk=i // 1000, video_key=k, episode_index=i))
                stream, times = frames(v)
                assert len(times) == length, f"{v}: {len(times)} frames for {length} rows"
                for j, t in enumerate(times):
                    assert abs(t - j / FPS) < TOL, f"{v} frame {j} at {t}"
                summary["videos"][k] = stream
            check_stats(ep_stats[i]["stats"], info, quantiles=False)
        assert first == info["total_frames"]
        check_stats(json.load(open(os.path.join(root, "meta/stats.json"))), info, quantiles=False)
        summary["tasks"] = [t["task"] for t in tasks]
    else:
        eps = pq.read_table(os.path.join(root, "meta/episodes/chunk-000/file-000.parquet")).to_pylist()
        tasks = pq.read_table(os.path.join(root, "meta/tasks.parquet"))
        pandas = tasks.schema.pandas_metadata
        assert pandas["index_columns"] == ["__index_level_0__"], pandas
        names = tasks.column("__index_level_0__").to_pylist()
        assert tasks.column("task_index").to_pylist() == list(range(len(names)))
        def sequence(files):
            """LeRobot's file order: file 0..999 of chunk 0, then chunk 1..."""
            want = [(g // 1000, g % 1000) for g in range(len(files))]
            assert sorted(files) == want, f"file indices {sorted(files)}"

        # Rows: each data file holds consecutive episodes, its first row the first one's.
        by_file = {}
        for e in eps:
            by_file.setdefault((e["data/chunk_index"], e["data/file_index"]), []).append(e)
        sequence(by_file)
        first = 0
        for (c, f), group in sorted(by_file.items()):
            path = os.path.join(root, info["data_path"].format(chunk_index=c, file_index=f))
            data = pq.read_table(path)
            check_schema(data.schema, sd, ad, ed)
            assert group[0]["dataset_from_index"] == first, f"{path} starts at {group[0]['dataset_from_index']}"
            check_rows(data, [(e["episode_index"], e["length"]) for e in group], first)
            first += data.num_rows
        assert first == info["total_frames"]
        for e in eps:
            assert e["dataset_to_index"] - e["dataset_from_index"] == e["length"]
        summary["data_files"] = len(by_file)
        summary["video_files"] = {}
        for k in video_keys:
            by_video = {}
            for e in eps:
                by_video.setdefault((e[f"videos/{k}/chunk_index"], e[f"videos/{k}/file_index"]), []).append(e)
            sequence(by_video)
            for (c, f), group in sorted(by_video.items()):
                v = os.path.join(root, info["video_path"].format(video_key=k, chunk_index=c, file_index=f))
                stream, times = frames(v)
                assert len(times) == sum(e["length"] for e in group), f"{v}: {len(times)} frames"
                offset = 0
                for e in group:
                    start = e[f"videos/{k}/from_timestamp"]
                    assert abs(start - offset / FPS) < TOL, f"{v}: episode {e['episode_index']} starts at {start}"
                    assert abs(e[f"videos/{k}/to_timestamp"] - start - e["length"] / FPS) < TOL
                    for j in range(e["length"]):
                        t = times[offset + j]
                        assert abs(t - (start + j / FPS)) < TOL, f"{v}: episode {e['episode_index']} frame {j} at {t}"
                    offset += e["length"]
                summary["videos"][k] = stream
            summary["video_files"][k] = len(by_video)
        check_stats(json.load(open(os.path.join(root, "meta/stats.json"))), info, quantiles=True)
        summary["tasks"] = names
    print(json.dumps(summary))


if __name__ == "__main__":
    main(sys.argv[1], sys.argv[2])
