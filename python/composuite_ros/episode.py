"""What both Gymnasium faces share, with no ROS in it: the spaces, the seeds of episodes and
what an episode's `info` says. `CompoSuiteRosEnv` (over the suite) and `CompoSuiteNativeEnv`
(in-process) fill `info` through the one `EpisodeTracker.record`, so a step gives the same
`info` on either path.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np
from gymnasium import spaces

# The flat observation's layout (composuite_msgs/Observation): the task one-hots sit at 45..60.
OBS_SIZE_WITH_TASK = 93
OBS_SIZE_WITHOUT_TASK = 77
TASK_ID_SLICE = slice(45, 61)
ACTION_SIZE = 8
ACTION_MODES = ("reference", "absolute")


def observation_space(use_task_id_obs: bool) -> spaces.Box:
    size = OBS_SIZE_WITH_TASK if use_task_id_obs else OBS_SIZE_WITHOUT_TASK
    return spaces.Box(-np.inf, np.inf, shape=(size,), dtype=np.float64)


def reference_action_space() -> spaces.Box:
    return spaces.Box(-1.0, 1.0, shape=(ACTION_SIZE,), dtype=np.float32)


def absolute_action_space(limits: Sequence[tuple[str, float, float]]) -> spaces.Box:
    """The absolute mode's space from `(name, lower, upper)` of the 7 arm joints and the left
    finger joint."""
    return spaces.Box(np.array([lo for _, lo, _ in limits]), np.array([hi for _, _, hi in limits]),
                      dtype=np.float64)


def check_action_mode(action_mode: str) -> None:
    if action_mode not in ACTION_MODES:
        raise ValueError(f"action_mode {action_mode!r} is not one of {', '.join(ACTION_MODES)}")


def check_action(values: np.ndarray, action_mode: str) -> None:
    """A ValueError naming what is wrong with one action (already float64, flattened)."""
    if values.shape != (ACTION_SIZE,):
        raise ValueError(f"action has {values.size} values; this env takes {ACTION_SIZE} "
                         f"({'7 joint deltas and the gripper, each in [-1, 1]' if action_mode == 'reference' else '7 joint targets (rad) and the left finger target (m)'})")
    if not np.all(np.isfinite(values)):
        raise ValueError(f"action has non-finite values: {values.tolist()}")


class EpisodeSeeds:
    """The seeds of an environment's episodes: a given seed, else the next draw of a generator
    seeded by the last given one (fresh entropy if none was given), as Gymnasium seeds an env's
    `np_random`. Retrying a reset with the same seed gives the same start."""

    def __init__(self):
        self._rng: np.random.Generator | None = None

    def next(self, seed: int | None) -> int:
        if seed is not None:
            if not 0 <= int(seed) < 2**64:
                raise ValueError(f"seed {seed} is outside 0..2**64-1")
            self._rng = np.random.default_rng(int(seed))
            return int(seed)
        if self._rng is None:
            self._rng = np.random.default_rng()
        return int(self._rng.integers(0, 2**31))


def vector_seeds(seed, num_envs: int) -> list[int | None]:
    """A vector env's `reset(seed=...)` as one seed (or None) per environment: an int s gives
    environment i the seed s + i (as Gymnasium's own vector envs do), a list one per environment,
    None the next seed of each environment's own sequence."""
    if seed is None:
        return [None] * num_envs
    if isinstance(seed, (int, np.integer)):
        return [int(seed) + i for i in range(num_envs)]
    seeds = list(seed)
    if len(seeds) != num_envs:
        raise ValueError(f"{len(seeds)} seeds for {num_envs} environments")
    return seeds


class EpisodeTracker:
    """What an episode has shown so far: return, success, furthest stage."""

    def __init__(self, start_stamp_ns: int = 0):
        self.start_stamp_ns = start_stamp_ns
        self.episode_return = 0.0
        self.success = False
        self.furthest_stage = -1
        self.done = False

    def record(self, *, stage_names: list[str], stage_values, current_stage: int, reward: float,
               success: bool, step: int, sim_time: float, reason: str, done: bool) -> dict[str, Any]:
        """Take one step's outcome; returns the step's info. The info is deterministic (same
        seed and actions, same info), so it has no episode counter or absolute clock, which go
        on across episodes."""
        current_stage = int(current_stage)
        self.episode_return += float(reward)
        self.success = self.success or bool(success)
        self.furthest_stage = max(self.furthest_stage, current_stage)
        self.done = done
        return {
            "stages": dict(zip(stage_names, (float(v) for v in stage_values))),
            "current_stage": stage_names[current_stage] if current_stage >= 0 else "",
            "furthest_stage": stage_names[self.furthest_stage] if self.furthest_stage >= 0 else "",
            "success": bool(success),
            "episode_success": self.success,
            "step": int(step),
            "sim_time": sim_time,
            "reason": reason,
        }
