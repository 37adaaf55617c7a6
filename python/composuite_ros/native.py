"""The environments in-process: the simulation core runs inside this Python process (the
compiled `composuite_ros._native`), no ROS, no DDS, no other process.

    import gymnasium, composuite_ros
    env = gymnasium.make("composuite_ros/CompoSuiteNative-v0", task="IIWA/box/no_obstacle/pick_place")
    observation, info = env.reset(seed=0)
    observation, reward, terminated, truncated, info = env.step(env.action_space.sample())

    envs = gymnasium.make_vec("composuite_ros/CompoSuiteNative-v0", num_envs=8,
                              tasks=["IIWA/box/no_obstacle/pick_place", "Jaco/plate/object_wall/shelf"] * 4)

`CompoSuiteNativeEnv` is `CompoSuiteRosEnv` without the suite: the same spaces, action modes,
seeding, termination, truncation and `info`, and for the same seed and actions the same
observations, rewards and `info`, bit for bit — so a policy trained here is evaluated over ROS 2
unchanged. `CompoSuiteNativeVectorEnv` steps N environments (tasks may differ) in one call into
Rust, on a thread pool with the GIL released; its results do not depend on the number of
threads.
"""

from __future__ import annotations

import os
from collections.abc import Sequence
from typing import Any

import gymnasium
import numpy as np
from gymnasium.vector import VectorEnv
from gymnasium.vector.utils import batch_space

from . import _native
from ._gymnasium import NEXT_STEP_AUTORESET
from .episode import (ACTION_SIZE, EpisodeSeeds, EpisodeTracker, absolute_action_space,
                      check_action, check_action_mode, observation_space, reference_action_space,
                      vector_seeds)
from .errors import EpisodeOverError
from .tasks import Task

DEFAULT_TASK = "IIWA/box/no_obstacle/pick_place"


def default_threads(num_envs: int) -> int:
    """One thread per environment, at most one per core this process may run on."""
    try:
        cores = len(os.sched_getaffinity(0))
    except AttributeError:  # not Linux
        cores = os.cpu_count() or 1
    return max(1, min(num_envs, cores))


def _task_name(task: str | Task) -> str:
    return str(Task.parse(task)) if not isinstance(task, str) else task


def record_row(tracker: EpisodeTracker, batch, index: int, stage_names: list[str],
               end_reasons: tuple[str, str], period_ns: int) -> tuple[float, bool, bool, dict[str, Any]]:
    """Environment `index`'s row of `batch` after a step, taken by its episode's `tracker`:
    (reward, terminated, truncated, info), the info as `CompoSuiteRosEnv` gives it.
    `end_reasons` is `_native.end_reasons(horizon)`: the objective's and the horizon's text."""
    terminated, truncated = bool(batch.terminated[index]), bool(batch.truncated[index])
    steps = int(batch.steps[index])
    reward = float(batch.rewards[index])
    lifted, at_horizon = end_reasons
    info = tracker.record(
        stage_names=stage_names, stage_values=batch.stage_values[index, :len(stage_names)],
        current_stage=batch.current_stage[index], reward=reward, success=batch.success[index],
        step=steps, sim_time=(steps * period_ns) * 1e-9,
        reason=lifted if terminated else at_horizon if truncated else "", done=terminated or truncated)
    return reward, terminated, truncated, info


class CompoSuiteNativeEnv(gymnasium.Env):
    """One environment in-process, with the reference's spaces (see the module docs).

    Args:
        task: `robot/object/obstacle/objective` (any accepted spelling; the reference's default
            task unless given).
        action_mode: "reference" (8 normalised values, the benchmark's) or "absolute" (7 joint
            targets in rad and the left finger joint's target in m).
        use_task_id_obs: include the 16 task one-hots (93 values) or not (77).
        horizon: episode length limit in control steps (500, as the reference's training).
        reward_shaping: staged rewards (True) or sparse ones (1 on success, else 0).
        reward_scale: multiplies every reward (1).
        render_mode: None, or "rgb_array": `render()` returns the scene as a `(height, width, 3)`
            uint8 array (Gymnasium's render API, which wrappers such as `RecordVideo` read),
            drawn on the CPU.
        render_camera: which of the reference's cameras `render()` looks through: "frontview"
            (default), "agentview", "birdview", "sideview" or "eye_in_hand".
        render_width, render_height: the picture's size in pixels (256 × 256).
    """

    metadata = {"render_modes": ["rgb_array"], "render_fps": 20}

    def __init__(self, task: str | Task = DEFAULT_TASK, *, action_mode: str = "reference",
                 use_task_id_obs: bool = True, horizon: int = 500, reward_shaping: bool = True,
                 reward_scale: float = 1.0, render_mode: str | None = None,
                 render_camera: str = "frontview", render_width: int = 256,
                 render_height: int = 256):
        check_action_mode(action_mode)
        if render_mode not in (None, *self.metadata["render_modes"]):
            raise ValueError(f"render_mode {render_mode!r}: use None or one of "
                             f"{self.metadata['render_modes']}")
        self.render_mode = render_mode
        self.render_camera = render_camera
        self.render_size = (render_width, render_height)
        self.action_mode = action_mode
        self.use_task_id_obs = use_task_id_obs
        self._batch = _native.Batch([_task_name(task)], threads=1, horizon=horizon,
                                    use_task_id_obs=use_task_id_obs, reward_shaping=reward_shaping,
                                    reward_scale=reward_scale, action_mode=action_mode)
        self._period_ns = self._batch.control_period_ns
        self._end_reasons = _native.end_reasons(self._batch.horizon)
        self.observation_space = observation_space(use_task_id_obs)
        self._on_new_task()
        self._seeds = EpisodeSeeds()
        self._tracker: EpisodeTracker | None = None
        self._clock_ns = 0
        # Views of the batch's buffers (one row each).
        b = self._batch
        self._modes, self._seed_in, self._action_in = b.modes, b.seeds, b.actions
        self._obs, self._steps = b.observations, b.steps
        if render_mode is not None:
            self.render()  # a bad camera name or size fails here, not at the first frame

    def render(self):
        """The scene now as a `(height, width, 3)` uint8 array with `render_mode="rgb_array"`;
        None without a render mode (Gymnasium's convention)."""
        if self.render_mode is None:
            return None
        width, height = self.render_size
        return self._batch.render(0, self.render_camera, width, height)

    # ---- the Gymnasium API ----------------------------------------------------------------------

    def reset(self, *, seed: int | None = None, options: dict | None = None):
        """Start an episode. `seed` fixes the object's start (the reference's `np.random.seed`
        then `reset()`); without one, the next seed of this env's own sequence."""
        super().reset(seed=seed)
        if options and "task" in options:
            self.set_task(options["task"])
        episode_seed = self._seeds.next(seed)
        self._modes[0] = _native.MODE_RESET
        self._seed_in[0] = episode_seed
        self._batch.run()
        self._tracker = EpisodeTracker()
        info = {"episode": self._batch.episode(0), "seed": episode_seed, "task": str(self.task),
                "sim_time": 0.0, "suite_time": self._clock_ns * 1e-9}
        return self._obs[0].copy(), info

    def step(self, action):
        if self._tracker is None:
            raise EpisodeOverError("step() before reset(): call reset() first")
        if self._tracker.done:
            raise EpisodeOverError(
                f"episode {self._batch.episode(0)} is over (after {int(self._steps[0])} steps); "
                "call reset() to start the next one")
        values = np.asarray(action, dtype=np.float64).reshape(-1)
        check_action(values, self.action_mode)
        self._action_in[0] = values
        self._modes[0] = _native.MODE_STEP
        self._batch.run()
        self._clock_ns += self._period_ns
        reward, terminated, truncated, info = record_row(
            self._tracker, self._batch, 0, self._stage_names, self._end_reasons, self._period_ns)
        return self._obs[0].copy(), reward, terminated, truncated, info

    # ---- beyond Gymnasium -----------------------------------------------------------------------

    def set_task(self, task: str | Task) -> Task:
        """Choose the task (ends the current episode; the next `reset()` starts one of it). A
        ValueError lists the valid choices for a name no axis knows."""
        self._batch.set_task(0, _task_name(task))
        self._on_new_task()
        self._tracker = None
        return self.task

    @property
    def episode(self) -> int:
        return self._batch.episode(0)

    @property
    def steps(self) -> int:
        return int(self._steps[0]) if self._tracker is not None else 0

    def _on_new_task(self) -> None:
        self.task = Task.parse(self._batch.tasks()[0])
        self._stage_names = list(self._batch.stage_names(0))
        if self.action_mode == "absolute":
            self.action_space = absolute_action_space(self._batch.joint_limits(0))
        else:
            self.action_space = reference_action_space()


class CompoSuiteNativeVectorEnv(VectorEnv):
    """N environments in-process, stepped together in Rust on `threads` threads, as a
    Gymnasium 1.x `VectorEnv` with next-step autoreset (as `CompoSuiteRosVectorEnv`).

    Args:
        tasks: one task for all, or one per environment (the paper's multi-task setting).
        num_envs: the number of environments (default: one per task given).
        threads: threads stepping them (default: one per environment, at most one per core).
        use_task_id_obs, horizon, reward_shaping, reward_scale: as `CompoSuiteNativeEnv`.
        copy: return fresh arrays from `reset`/`step` (True, as Gymnasium's own vector envs);
            False returns the batch's own buffers, overwritten by the next call.
        render_mode, render_camera, render_width, render_height: as `CompoSuiteNativeEnv`;
            `render()` returns one frame per environment, a tuple of `(height, width, 3)` uint8
            arrays (Gymnasium's vector convention, what its vector `RecordVideo` tiles).

    Actions are the reference benchmark's (8 values in [-1, 1] per environment). Autoreset: when
    environment i ends an episode, the next `step()` ignores its action, resets it (the next
    seed of its own sequence) and returns the new episode's first observation with reward 0 and
    terminated = truncated = False, with that reset's info.
    """

    metadata = {**NEXT_STEP_AUTORESET, "render_modes": ["rgb_array"], "render_fps": 20}

    def __init__(self, tasks: str | Task | Sequence[str | Task] = DEFAULT_TASK,
                 num_envs: int | None = None, *, threads: int | None = None,
                 use_task_id_obs: bool = True, horizon: int = 500, reward_shaping: bool = True,
                 reward_scale: float = 1.0, copy: bool = True, render_mode: str | None = None,
                 render_camera: str = "frontview", render_width: int = 256, render_height: int = 256,
                 **kwargs):
        # make_vec passes the spec's max_episode_steps (None unless registered with one).
        kwargs.pop("max_episode_steps", None)
        if kwargs:
            raise TypeError(f"unexpected arguments: {', '.join(sorted(kwargs))}")
        if render_mode not in (None, *self.metadata["render_modes"]):
            raise ValueError(f"render_mode {render_mode!r}: use None or one of {self.metadata['render_modes']}")
        self.render_mode = render_mode
        self.render_camera = render_camera
        self.render_size = (render_width, render_height)
        if isinstance(tasks, (str, Task)):
            tasks = [tasks] * (1 if num_envs is None else num_envs)
        tasks = [_task_name(t) for t in tasks]
        if num_envs is not None and len(tasks) != num_envs:
            raise ValueError(f"{len(tasks)} tasks for num_envs={num_envs}; give one task or one per environment")
        if not tasks:
            raise ValueError("no environments: give at least one task")
        self.num_envs = len(tasks)
        self._batch = _native.Batch(tasks, threads=threads or default_threads(self.num_envs),
                                    horizon=horizon, use_task_id_obs=use_task_id_obs,
                                    reward_shaping=reward_shaping, reward_scale=reward_scale)
        self.use_task_id_obs = use_task_id_obs
        self.copy = copy
        self.single_observation_space = observation_space(use_task_id_obs)
        self.single_action_space = reference_action_space()
        self.observation_space = batch_space(self.single_observation_space, self.num_envs)
        self.action_space = batch_space(self.single_action_space, self.num_envs)
        self._period_ns = self._batch.control_period_ns
        self._lifted_reason, self._horizon_reason = _native.end_reasons(self._batch.horizon)
        self._seeds = [EpisodeSeeds() for _ in range(self.num_envs)]
        self._started = False
        self._autoreset = np.zeros(self.num_envs, dtype=bool)
        self._episode_success = np.zeros(self.num_envs, dtype=bool)
        self._furthest = np.full(self.num_envs, -1, dtype=np.int64)
        self._clock_ns = np.zeros(self.num_envs, dtype=np.int64)
        self._index = np.arange(self.num_envs)
        self._on_new_tasks()
        if render_mode is not None:
            self.render()  # a bad camera name or size fails here, not at the first frame

    def render(self) -> tuple[np.ndarray, ...] | None:
        """Every environment's scene now, a tuple of `(height, width, 3)` uint8 arrays in
        environment order, with `render_mode="rgb_array"`; None without a render mode."""
        if self.render_mode is None:
            return None
        width, height = self.render_size
        return tuple(self._batch.render(i, self.render_camera, width, height) for i in range(self.num_envs))

    @property
    def threads(self) -> int:
        return self._batch.threads

    @property
    def horizon(self) -> int:
        """Episode length limit in control steps."""
        return int(self._batch.horizon)

    @property
    def tasks(self) -> list[Task]:
        return [Task.parse(t) for t in self._batch.tasks()]

    def set_task(self, index: int, task: str | Task) -> Task:
        """Give environment `index` a task (its episode ends; the next reset starts the new one)."""
        self._batch.set_task(index, _task_name(task))
        self._on_new_tasks()
        self._started = False
        return self.tasks[index]

    def _on_new_tasks(self) -> None:
        """The stage-name tables the `info` is built from: for each stage name in the batch,
        the column it has in each environment's `stage_values` row (-1 where its objective has
        no such stage)."""
        names = [list(self._batch.stage_names(i)) for i in range(self.num_envs)]
        self._stage_columns: dict[str, np.ndarray] = {}
        for i, env_names in enumerate(names):
            for column, name in enumerate(env_names):
                self._stage_columns.setdefault(name, np.full(self.num_envs, -1, dtype=np.int64))[i] = column
        # Row i: env i's stage names, then "" for "no stage" (index -1).
        width = _native.MAX_STAGES + 1
        self._stage_name_table = np.full((self.num_envs, width), "", dtype=object)
        for i, env_names in enumerate(names):
            self._stage_name_table[i, :len(env_names)] = env_names
        self._task_names = np.array([str(t) for t in self.tasks], dtype=object)

    # ---- resets -------------------------------------------------------------------------------

    def reset(self, *, seed: int | list[int | None] | None = None, options: dict | None = None):
        """Reset every environment. `seed`: an int s gives environment i the seed s + i (as
        Gymnasium's own vector envs do), a list one seed per environment."""
        super().reset(seed=seed if isinstance(seed, int) else None)
        seeds = vector_seeds(seed, self.num_envs)
        if options and "tasks" in options:
            for i, task in enumerate(options["tasks"]):
                self.set_task(i, task)
        b = self._batch
        b.seeds[:] = [self._seeds[i].next(s) for i, s in enumerate(seeds)]
        b.modes[:] = _native.MODE_RESET
        b.run()
        self._started = True
        self._autoreset[:] = False
        self._episode_success[:] = False
        self._furthest[:] = -1
        infos = self._reset_info(np.ones(self.num_envs, dtype=bool))
        return self._out(b.observations), infos

    # ---- steps --------------------------------------------------------------------------------

    def step(self, actions):
        if not self._started:
            raise EpisodeOverError("step() before reset(): call reset() first")
        actions = np.asarray(actions, dtype=np.float64)
        if actions.shape != (self.num_envs, ACTION_SIZE):
            raise ValueError(f"actions have shape {actions.shape}; expected ({self.num_envs}, 8): "
                             "per environment 7 joint deltas and the gripper, each in [-1, 1]")
        if not np.all(np.isfinite(actions)):
            raise ValueError("actions have non-finite values")
        b = self._batch
        resetting = self._autoreset.copy()
        if resetting.any():
            for i in np.flatnonzero(resetting):
                b.seeds[i] = self._seeds[i].next(None)
        b.modes[:] = np.where(resetting, _native.MODE_RESET, _native.MODE_STEP)
        b.actions[:] = actions
        b.run()
        stepped = ~resetting
        self._clock_ns[stepped] += self._period_ns
        terminations, truncations = b.terminated, b.truncated
        infos = self._step_info(stepped)
        if resetting.any():
            infos = _merge_infos(infos, self._reset_info(resetting))
        self._autoreset = terminations | truncations
        return (self._out(b.observations), self._out(b.rewards), self._out(terminations),
                self._out(truncations), infos)

    def _out(self, array: np.ndarray) -> np.ndarray:
        return array.copy() if self.copy else array

    # ---- info, built from the batch's arrays (the layout Gymnasium's `_add_info` gives) ---------

    def _reset_info(self, rows: np.ndarray) -> dict[str, Any]:
        b = self._batch
        self._episode_success[rows] = False
        self._furthest[rows] = -1
        episodes = np.zeros(self.num_envs, dtype=np.int64)
        for i in np.flatnonzero(rows):  # episode counters live in Rust; only resetting rows
            episodes[i] = b.episode(int(i))
        seeds = np.where(rows, b.seeds, 0).astype(np.int64)
        tasks = np.where(rows, self._task_names, None)
        return {"episode": episodes, "_episode": rows.copy(), "seed": seeds, "_seed": rows.copy(),
                "task": tasks, "_task": rows.copy(), "sim_time": np.zeros(self.num_envs),
                "_sim_time": rows.copy(),
                "suite_time": np.where(rows, self._clock_ns * 1e-9, 0.0),
                "_suite_time": rows.copy()}

    def _step_info(self, rows: np.ndarray) -> dict[str, Any]:
        if not rows.any():
            return {}
        b = self._batch
        current = b.current_stage.astype(np.int64)
        success = b.success
        self._episode_success[rows] |= success[rows]
        self._furthest[rows] = np.maximum(self._furthest[rows], current[rows])
        stages: dict[str, Any] = {}
        for name, columns in self._stage_columns.items():
            present = rows & (columns >= 0)
            if not present.any():
                continue
            stages[name] = np.where(present, b.stage_values[self._index, np.maximum(columns, 0)], 0.0)
            stages[f"_{name}"] = present
        names = self._stage_name_table
        reason = np.where(b.terminated, self._lifted_reason,
                          np.where(b.truncated, self._horizon_reason, "")).astype(object)
        steps = b.steps.astype(np.int64)
        return {
            "stages": stages, "_stages": rows.copy(),
            "current_stage": np.where(rows, names[self._index, current], None),
            "_current_stage": rows.copy(),
            "furthest_stage": np.where(rows, names[self._index, self._furthest], None),
            "_furthest_stage": rows.copy(),
            "success": np.where(rows, success, False), "_success": rows.copy(),
            "episode_success": np.where(rows, self._episode_success, False),
            "_episode_success": rows.copy(),
            "step": np.where(rows, steps, 0), "_step": rows.copy(),
            "sim_time": np.where(rows, (steps * self._period_ns) * 1e-9, 0.0),
            "_sim_time": rows.copy(),
            "reason": np.where(rows, reason, None), "_reason": rows.copy(),
        }


def _merge_infos(step: dict[str, Any], reset: dict[str, Any]) -> dict[str, Any]:
    """One info dict from a step's rows and the autoreset rows' (a key both have, e.g.
    `sim_time`, takes each row from the side whose mask holds it)."""
    merged = dict(step)
    for key, value in reset.items():
        if key.startswith("_"):
            continue
        mask = reset[f"_{key}"]
        if key in merged:
            merged[key] = np.where(mask, value, merged[key])
            merged[f"_{key}"] = merged[f"_{key}"] | mask
        else:
            merged[key], merged[f"_{key}"] = value, mask.copy()
    return merged
