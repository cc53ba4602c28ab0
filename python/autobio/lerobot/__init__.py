"""LeRobot policies on autobio tasks (needs ``lerobot`` 0.4.x: ``pip install 'autobio[lerobot]'``).

A package, not a module, because ``lerobot-eval --env.discover_packages_path=autobio.lerobot``
imports the package it is given and walks its ``__path__``.

- ``load_policy(path)``: any LeRobot checkpoint (a ``pretrained_model`` folder that
  ``lerobot-train`` wrote: ACT, diffusion, or whatever else ``lerobot`` makes from a config) with
  its own pre- and post-processors (normalisation, batching, device), as a ``Runner``.
- ``Runner.act(observation)``: one action from a gym-style observation (``pixels``,
  ``environment_state``, ``agent_pos``; what ``autobio.make`` returns), exactly as
  ``lerobot-eval`` turns an observation into an action (its ``preprocess_observation``, the
  policy's preprocessor, ``select_action`` with the policy's own action queue, the
  postprocessor). ``Runner.reset()`` between episodes.
- ``AutobioEnv`` (registered as the ``autobio`` env type on import), so LeRobot's own
  ``lerobot-eval`` runs a checkpoint on an autobio task:
  ``lerobot-eval --env.discover_packages_path=autobio.lerobot --env.type=autobio
  --env.task=thermal_cycler.close_lid --env.obs_type=environment_state_agent_pos
  --policy.path=CHECKPOINT --eval.n_episodes=10 --eval.batch_size=1``.

``python -m autobio.serve`` serves a checkpoint to ``autobio eval --model`` (docs/baseline.md).
"""

from dataclasses import dataclass, field

import numpy as np

try:
    import torch
    from lerobot.configs.policies import PreTrainedConfig
    from lerobot.configs.types import FeatureType, PolicyFeature
    from lerobot.envs.configs import EnvConfig
    from lerobot.policies.factory import get_policy_class, make_pre_post_processors
except ImportError as e:  # pragma: no cover - the module needs lerobot
    raise ImportError("autobio.lerobot needs lerobot 0.4: pip install 'autobio[lerobot]'") from e

from .. import _core


def to_batch(observation, task=None):
    """A gym-style observation as LeRobot's batch of tensors (``lerobot-eval``'s
    ``preprocess_observation``): images to float CHW in [0, 1] under
    ``observation.images.<camera>``, ``environment_state`` and ``agent_pos`` to float32 under
    ``observation.environment_state`` and ``observation.state``, each with a batch dimension of
    one; ``task`` (the instruction) as a one-element list, for language-conditioned policies."""
    batch = {}
    for camera, img in (observation.get("pixels") or {}).items():
        t = torch.from_numpy(np.ascontiguousarray(img))
        if t.ndim == 3:
            t = t.unsqueeze(0)
        if t.dtype != torch.uint8:
            raise ValueError(f"image {camera}: expected uint8 HWC, got {t.dtype}")
        batch[f"observation.images.{camera}"] = t.permute(0, 3, 1, 2).float() / 255.0
    for key, name in (("environment_state", "observation.environment_state"),
                      ("agent_pos", "observation.state")):
        if key in observation:
            t = torch.as_tensor(np.asarray(observation[key]), dtype=torch.float32)
            batch[name] = t.unsqueeze(0) if t.ndim == 1 else t
    if task is not None:
        batch["task"] = [task]
    return batch


class Runner:
    """A loaded LeRobot policy with its processors: ``act`` one observation at a time.

    ``bounds``: the smallest and largest action of the demonstrations the policy was trained on
    (the dataset statistics saved with its post-processor), or None where none were saved; with
    ``clip``, each action is clipped to them, so a regression that overshoots a gripper's end
    stop by a hair (255.3 of 0..255) stays inside the actuators' ranges, which autobio refuses
    to clamp."""

    def __init__(self, policy, preprocessor, postprocessor, config, path, clip=True):
        self.policy = policy
        self.preprocessor = preprocessor
        self.postprocessor = postprocessor
        self.config = config
        self.path = str(path)
        self.bounds = demonstrated_action_bounds(self.path)
        self.clip = clip and self.bounds is not None

    @property
    def input_features(self):
        """The policy's input features (name to shape), e.g. ``observation.environment_state``."""
        return {k: tuple(v.shape) for k, v in self.config.input_features.items()}

    @property
    def reads_environment_state(self):
        """Whether the policy reads the privileged environment state (a state-based policy)."""
        return "observation.environment_state" in self.config.input_features

    def reset(self):
        """Clears the policy's action queue and history: call before each episode."""
        self.policy.reset()

    @torch.no_grad()
    def act(self, observation, task=None):
        """One action (float64, the task's action layout) for a gym-style observation."""
        batch = self.preprocessor(to_batch(observation, task))
        action = self.policy.select_action(batch)
        action = self.postprocessor(action)
        action = action.to("cpu").numpy().astype(np.float64).reshape(-1)
        if self.clip:
            action = np.clip(action, self.bounds[0], self.bounds[1])
        return action


    @torch.no_grad()
    def first_actions(self, observations, task=None, batch_size=256):
        """For a batch of observations (arrays with a leading frame axis, no camera), the first
        action the policy would take from each with an empty action queue: one forward pass per
        ``batch_size`` frames where the policy predicts chunks from one frame (ACT), else one
        ``reset`` and ``act`` per frame."""
        n = len(next(iter(observations.values())))
        if self.config.type != "act":
            out = []
            for i in range(n):
                self.reset()
                out.append(self.act({k: v[i] for k, v in observations.items()}, task))
            self.reset()
            return np.asarray(out)
        out = []
        for i in range(0, n, batch_size):
            part = {k: np.asarray(v[i : i + batch_size]) for k, v in observations.items()}
            batch = to_batch(part)
            if task is not None:
                batch["task"] = [task] * len(part["agent_pos"])
            batch = self.preprocessor(batch)
            chunk = self.policy.predict_action_chunk(batch)
            action = self.postprocessor(chunk[:, 0])
            out.append(action.to("cpu").numpy().astype(np.float64))
        actions = np.concatenate(out)
        if self.clip:
            actions = np.clip(actions, self.bounds[0], self.bounds[1])
        return actions


def demonstrated_action_bounds(path):
    """(min, max) of the training dataset's actions, from the statistics a checkpoint's
    post-processor saved (``policy_postprocessor_step_*_unnormalizer_processor.safetensors``)."""
    import glob
    import os

    from safetensors.numpy import load_file

    for f in sorted(glob.glob(os.path.join(path, "policy_postprocessor_step_*.safetensors"))):
        stats = load_file(f)
        if "action.min" in stats and "action.max" in stats:
            return stats["action.min"].astype(np.float64), stats["action.max"].astype(np.float64)
    return None


def load_policy(path, device="cpu", clip=True):
    """A LeRobot checkpoint (``.../checkpoints/<step>/pretrained_model``) as a ``Runner``, with
    the pre- and post-processors saved beside it (``clip``: see ``Runner``)."""
    path = str(path)
    config = PreTrainedConfig.from_pretrained(path)
    config.device = device
    policy = get_policy_class(config.type).from_pretrained(path, config=config)
    policy.to(device)
    policy.eval()
    preprocessor, postprocessor = make_pre_post_processors(
        config,
        pretrained_path=path,
        preprocessor_overrides={"device_processor": {"device": device}},
    )
    return Runner(policy, preprocessor, postprocessor, config, path, clip=clip)


@EnvConfig.register_subclass("autobio")
@dataclass
class AutobioEnv(EnvConfig):
    """An autobio task for ``lerobot-eval`` (``--env.type=autobio --env.task=<task id>``).
    ``obs_type`` is ``autobio.make``'s; the features are the task's own layouts."""

    task: str | None = "thermal_cycler.close_lid"
    fps: int = 50
    obs_type: str = "pixels_agent_pos"
    image_size: int = 224
    features: dict[str, PolicyFeature] = field(default_factory=dict)
    features_map: dict[str, str] = field(default_factory=dict)

    def __post_init__(self):
        info = _core.task_info(self.task)
        self.features = {
            "action": PolicyFeature(type=FeatureType.ACTION, shape=(len(info["action_names"]),))
        }
        self.features_map = {"action": "action"}
        if self.obs_type.endswith("agent_pos"):
            self.features["agent_pos"] = PolicyFeature(
                type=FeatureType.STATE, shape=(len(info["state_names"]),)
            )
            self.features_map["agent_pos"] = "observation.state"
        if "environment_state" in self.obs_type:
            self.features["environment_state"] = PolicyFeature(
                type=FeatureType.ENV, shape=(len(info["environment_state_names"]),)
            )
            self.features_map["environment_state"] = "observation.environment_state"
        if self.obs_type.startswith("pixels"):
            for camera in info["cameras"]:
                key = camera.replace("/", "_")
                self.features[f"pixels/{key}"] = PolicyFeature(
                    type=FeatureType.VISUAL, shape=(self.image_size, self.image_size, 3)
                )
                self.features_map[f"pixels/{key}"] = f"observation.images.{key}"

    @property
    def package_name(self):
        return "autobio"

    @property
    def gym_id(self):
        return f"autobio/{self.task}-v0"

    @property
    def gym_kwargs(self):
        # lerobot-eval steps the env with the policy's raw output, which overshoots an end stop
        # by a hair (`Runner` clips for the same reason); autobio's env refuses that unless told.
        return {"obs_type": self.obs_type, "image_size": self.image_size, "clip_actions": True}
