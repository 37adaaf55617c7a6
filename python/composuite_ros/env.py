"""`CompoSuiteRosEnv`: one environment of a running CompoSuite-ROS suite as a `gymnasium.Env`.

    composuite launch --task IIWA/box/no_obstacle/pick_place &          # the suite (lockstep)

    import gymnasium, composuite_ros
    env = gymnasium.make("composuite_ros/CompoSuite-v0", task="IIWA/box/no_obstacle/pick_place")
    observation, info = env.reset(seed=0)
    for _ in range(500):
        observation, reward, terminated, truncated, info = env.step(env.action_space.sample())
        if terminated or truncated:
            observation, info = env.reset()
    env.close()

The spaces are the reference benchmark's (CompoSuite's `composuite.make(...)` through its Gym
wrapper): a 93-value observation (77 without the task one-hots, `use_task_id_obs=False`) and 8
actions in [-1, 1] — seven joint deltas (the goal is the measured joint position + 0.05 rad per
unit) and the gripper (close when > 0, open when < 0). `action_mode="absolute"` takes absolute
joint targets (rad) and the left finger joint's target (m) instead, within the URDF's limits.

Episodes end as in the reference: truncated at the horizon (500 steps), terminated early only by
Push when the object is lifted more than 10 cm. `info` carries every stage value (`stages`), the
current and furthest stage, `success` (reward 1 at this step), `episode_success` (at any step so
far), the step and the sim time since the reset (`sim_time`, s); the reset's info the episode
number, seed, task and the suite's clock (`suite_time`, s).
"""

from __future__ import annotations

from typing import Any

import gymnasium
import numpy as np
from gymnasium import spaces

from ._link import ARM_JOINTS, Channel, ObservationView, Participant, normalize_namespace
from .errors import EpisodeOverError
from .tasks import Task

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


def _view(message) -> ObservationView:
    return message if isinstance(message, ObservationView) else ObservationView.of_message(message)


def flat_observation(message, use_task_id_obs: bool) -> np.ndarray:
    """The observation vector an agent gets, from a composuite_msgs/Observation (or its view)."""
    view = _view(message)
    flat = view.flat
    if view.includes_task and not use_task_id_obs:
        return np.concatenate([flat[:TASK_ID_SLICE.start], flat[TASK_ID_SLICE.stop:]])
    if not view.includes_task and use_task_id_obs:
        return np.concatenate([flat[:TASK_ID_SLICE.start], view.task_one_hots, flat[TASK_ID_SLICE.start:]])
    return flat.copy()


def check_action_mode(action_mode: str) -> None:
    if action_mode not in ACTION_MODES:
        raise ValueError(f"action_mode {action_mode!r} is not one of {', '.join(ACTION_MODES)}")


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


class EpisodeTracker:
    """What an episode has shown so far: return, success, furthest stage."""

    def __init__(self, start_stamp_ns: int):
        self.start_stamp_ns = start_stamp_ns
        self.episode_return = 0.0
        self.success = False
        self.furthest_stage = -1
        self.done = False

    def step_info(self, messages) -> dict[str, Any]:
        """The step's info: deterministic (same seed and actions, same info), so no episode
        counter or absolute clock, which go on across episodes."""
        reward, status = messages.reward, messages.status
        self.episode_return += reward.total
        self.success = self.success or bool(reward.success)
        self.furthest_stage = max(self.furthest_stage, reward.current_stage)
        self.done = bool(status.done or status.terminated or status.truncated)
        names = list(reward.stage_names)
        return {
            "stages": dict(zip(names, (float(v) for v in reward.stage_values))),
            "current_stage": names[reward.current_stage] if reward.current_stage >= 0 else "",
            "furthest_stage": names[self.furthest_stage] if self.furthest_stage >= 0 else "",
            "success": bool(reward.success),
            "episode_success": self.success,
            "step": int(status.step),
            "sim_time": (stamp_ns(messages.observation) - self.start_stamp_ns) * 1e-9,
            "reason": status.reason_text,
        }


def stamp_ns(message) -> int:
    """An observation's header stamp (the suite's sim time) in integer nanoseconds."""
    return _view(message).stamp_ns


class CompoSuiteRosEnv(gymnasium.Env):
    """One environment of the suite (by namespace) in lockstep, with the reference's spaces.

    Args:
        task: `robot/object/obstacle/objective` to set first (None: keep the suite's task).
        namespace: the environment's namespace (`/` for a plain `composuite launch`,
            `/env_00`... for `--envs N`).
        action_mode: "reference" (8 normalised values, the benchmark's) or "absolute".
        use_task_id_obs: include the 16 task one-hots (93 values) or not (77).
        domain_id: ROS_DOMAIN_ID (default: the environment variable, else 0).
        timeout: seconds any wait may take before it raises, naming what it waited for (the
            first contact with the suite, discovery, may take 3 times as long).
    """

    metadata = {"render_modes": []}

    def __init__(self, task: str | Task | None = None, namespace: str = "/", *,
                 action_mode: str = "reference", use_task_id_obs: bool = True,
                 domain_id: int | None = None, timeout: float = 10.0, render_mode=None):
        check_action_mode(action_mode)
        if render_mode is not None:
            raise ValueError("CompoSuiteRosEnv does not render (use RViz or Foxglove on the suite's "
                             "topics); render_mode must be None")
        self.namespace = normalize_namespace(namespace)
        self.action_mode = action_mode
        self.use_task_id_obs = use_task_id_obs
        self.observation_space = observation_space(use_task_id_obs)
        self.action_space = reference_action_space()
        self._participant = Participant("composuite_gym", domain_id)
        try:
            self._channel = Channel(self._participant, self.namespace, timeout)
            self.task: Task | None = None
            if task is not None:
                self.set_task(task)
            elif action_mode == "absolute":
                raise ValueError("action_mode='absolute' needs a task (its robot fixes the joint "
                                 "names and limits of the action space)")
        except BaseException:
            self._participant.close()
            raise
        self._seeds = EpisodeSeeds()
        self._tracker: EpisodeTracker | None = None

    # ---- the Gymnasium API ----------------------------------------------------------------------

    def reset(self, *, seed: int | None = None, options: dict | None = None):
        """Start an episode. `seed` fixes the object's start (the reference's `np.random.seed`
        then `reset()`); without one, the next seed of this env's own sequence (see
        `EpisodeSeeds`)."""
        super().reset(seed=seed)
        if options and "task" in options:
            self.set_task(options["task"])
        reply = self._channel.reset(self._seeds.next(seed))
        self._tracker = EpisodeTracker(stamp_ns(reply.observation))
        info = {"episode": int(reply.episode), "seed": int(reply.seed), "task": str(self.task or ""),
                "sim_time": 0.0, "suite_time": stamp_ns(reply.observation) * 1e-9}
        return flat_observation(reply.observation, self.use_task_id_obs), info

    def step(self, action):
        if self._tracker is None:
            raise EpisodeOverError("step() before reset(): call reset() first")
        if self._tracker.done:
            raise EpisodeOverError(
                f"episode {self._channel.episode} in {self.namespace} is over "
                f"(after {self._channel.step_count} steps); call reset() to start the next one")
        self._send(action)
        if not self._participant.take_for(self._channel.step_arrived, self._channel.timeout,
                                          self._channel.step_subscriptions()):
            raise self._channel.step_lost_error()
        messages = self._channel.take_step()
        info = self._tracker.step_info(messages)
        status = messages.status
        return (flat_observation(messages.observation, self.use_task_id_obs),
                float(messages.reward.total), bool(status.terminated), bool(status.truncated), info)

    def close(self) -> None:
        """Leave the ROS graph: no node, participant or thread of this env remains."""
        self._participant.close()

    # ---- beyond Gymnasium -----------------------------------------------------------------------

    def set_task(self, task: str | Task) -> Task:
        """Choose the task (ends the current episode; the next `reset()` starts one of it). A
        ValueError lists the valid choices when the suite does not know a name."""
        parsed = Task.parse(task)
        self._channel.wait_ready()
        self.task = self._channel.set_task(parsed)
        self._tracker = None
        if self.action_mode == "absolute":
            self._use_robot_limits(self.task.robot)
        return self.task

    @property
    def timeout(self) -> float:
        """Seconds any wait may take (settable, e.g. short once the suite is known to run)."""
        return self._channel.timeout

    @timeout.setter
    def timeout(self, seconds: float) -> None:
        self._channel.timeout = float(seconds)

    @property
    def episode(self) -> int:
        return self._channel.episode

    @property
    def steps(self) -> int:
        return self._channel.step_count

    # ---- actions ------------------------------------------------------------------------------

    def _use_robot_limits(self, robot: str) -> None:
        limits = self._channel.joint_limits(robot)
        self._joint_names = [name for name, _, _ in limits]
        self.action_space = spaces.Box(np.array([lo for _, lo, _ in limits]),
                                       np.array([hi for _, _, hi in limits]), dtype=np.float64)

    def _send(self, action) -> None:
        values = np.asarray(action, dtype=np.float64).reshape(-1)
        if values.shape != (ACTION_SIZE,):
            raise ValueError(f"action has {values.size} values; this env takes {ACTION_SIZE} "
                             f"({'7 joint deltas and the gripper, each in [-1, 1]' if self.action_mode == 'reference' else '7 joint targets (rad) and the left finger target (m)'})")
        if not np.all(np.isfinite(values)):
            raise ValueError(f"action has non-finite values: {values.tolist()}")
        if self.action_mode == "reference":
            self._channel.send_reference_action(values)
        else:
            self._channel.send_joint_targets(self._joint_names, values[:ARM_JOINTS + 1])


def register_envs() -> None:
    """Register `composuite_ros/CompoSuite-v0` with Gymnasium (done on `import composuite_ros`)."""
    if "composuite_ros/CompoSuite-v0" not in gymnasium.registry:
        gymnasium.register(id="composuite_ros/CompoSuite-v0",
                           entry_point="composuite_ros.env:CompoSuiteRosEnv",
                           disable_env_checker=False)
