"""The scripted expert's actions for the reference model servers, read from the MCAP recordings
`autobio eval --policy expert --record` writes (`<task>_seed<seed>.mcap`), with Foxglove's own
MCAP reader. A server holding these answers as the expert would; the tests use it to check that
autobio's clients, not the expert, decide what the harness sees."""

import json
import os

from mcap.reader import make_reader


class Episode:
    """One recorded episode: its instruction and every control step's action (all robots,
    concatenated in task order)."""

    def __init__(self, path):
        per_robot = {}
        robots = []
        with open(path, "rb") as f:
            for _schema, channel, message in make_reader(f).iter_messages():
                topic = channel.topic
                if topic == "/task":
                    task = json.loads(message.data)
                    robots = [r["name"] for r in task["task"]["robots"]]
                    self.instruction = task["instance"]["instruction"]
                    self.stage_instructions = task["instance"].get("stage_instructions", [])
                elif topic.startswith("/robot/") and topic.endswith("/action"):
                    name = topic[len("/robot/"):-len("/action")]
                    per_robot.setdefault(name, []).append(json.loads(message.data)["action"])
        steps = min(len(per_robot[r]) for r in robots)
        self.actions = [sum((per_robot[r][k] for r in robots), []) for k in range(steps)]

    def chunk(self, start, length):
        """`length` actions from `start`, the last one repeated past the end (the arm holds)."""
        last = len(self.actions) - 1
        return [self.actions[min(start + k, last)] for k in range(length)]


class Library:
    """Recorded episodes by (task id, seed), loaded on first use."""

    def __init__(self, folder):
        self.folder = folder
        self.cache = {}

    def episode(self, task_id, seed):
        key = (str(task_id), int(seed))
        if key not in self.cache:
            path = os.path.join(self.folder, f"{key[0]}_seed{key[1]}.mcap")
            self.cache[key] = Episode(path)
        return self.cache[key]
