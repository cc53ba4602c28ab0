"""Loads a local dataset with the real `lerobot` (LeRobotDataset, its own video decoding) and
prints what it found as JSON: frames, episodes, and each camera's first frame's shape and mean.
Usage: load_lerobot.py DATASET_DIR"""
import json
import sys

from lerobot.datasets.lerobot_dataset import LeRobotDataset

root = sys.argv[1]
ds = LeRobotDataset("local/photoreal", root=root)
first = ds[0]
last = ds[len(ds) - 1]
cameras = {}
for key in ds.meta.camera_keys:
    frame = first[key]
    cameras[key] = {"shape": list(frame.shape), "mean": float(frame.float().mean()),
                    "last_mean": float(last[key].float().mean())}
print(json.dumps({
    "frames": len(ds),
    "episodes": ds.num_episodes,
    "fps": ds.fps,
    "task": first["task"],
    "cameras": cameras,
}))
