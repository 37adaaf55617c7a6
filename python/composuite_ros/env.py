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

With `render_mode="rgb_array"`, `render()` draws the last observation the suite sent (the arm's
joints, the fingers and the object's pose, and the task its one-hots name) with the same
renderer as the in-process env, here in this process (composuite_ros' native module): a frame
costs no bandwidth and shows exactly the step the observation is of.
"""

from __future__ import annotations

from typing import Any

import gymnasium
import numpy as np

from . import episode
from ._link import ARM_JOINTS, Channel, ObservationView, Participant, normalize_namespace
from .episode import (ACTION_MODES, ACTION_SIZE, OBS_SIZE_WITH_TASK, OBS_SIZE_WITHOUT_TASK,  # noqa: F401
                      TASK_ID_SLICE, EpisodeSeeds, absolute_action_space, check_action,
                      check_action_mode, observation_space, reference_action_space)
from .errors import EpisodeOverError
from .tasks import Task


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


class EpisodeTracker(episode.EpisodeTracker):
    """An episode's tracker fed by the suite's messages."""

    def step_info(self, messages) -> dict[str, Any]:
        reward, status = messages.reward, messages.status
        return self.record(
            stage_names=list(reward.stage_names), stage_values=reward.stage_values,
            current_stage=reward.current_stage, reward=reward.total, success=reward.success,
            step=status.step, sim_time=(stamp_ns(messages.observation) - self.start_stamp_ns) * 1e-9,
            reason=status.reason_text, done=bool(status.done or status.terminated or status.truncated))


def _native():
    """composuite_ros' native module, which draws the frames; a clear error if it is missing."""
    try:
        from . import _native as native
    except ImportError as e:
        raise ImportError("render_mode='rgb_array' draws with composuite_ros' native module, which is "
                          "not built here (`pip install ./python` builds it with the Rust toolchain)") from e
    return native


class ObservationDrawer:
    """Frames of the scene observations describe, through one camera at one size, drawn in this
    process by the native module (the envs over ROS render with it; see the module doc)."""

    def __init__(self, camera: str, width: int, height: int):
        _native().check_render(camera, width, height)  # a bad camera or size fails when made
        self.camera, self.width, self.height = camera, width, height
        self._renderers: dict[str, Any] = {}

    def draw(self, observation) -> np.ndarray:
        """The scene of `observation` (a composuite_msgs/Observation or its view) as a
        `(height, width, 3)` uint8 array; the task is the one its one-hots name."""
        if observation is None:
            raise gymnasium.error.ResetNeeded("render() before reset(): there is no observation to draw yet")
        view = _view(observation)
        native = _native()
        task = native.task_of_one_hots([float(v) for v in view.task_one_hots])
        if task not in self._renderers:
            self._renderers[task] = native.StateRenderer(task)
        return self._renderers[task].render(view.flat, self.camera, self.width, self.height)


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
        render_mode: None, or "rgb_array": `render()` returns the scene of the last observation
            as a `(height, width, 3)` uint8 array (see the module doc).
        render_camera: "frontview" (default), "agentview", "birdview", "sideview" or
            "eye_in_hand".
        render_width, render_height: the picture's size in pixels (256 × 256).
    """

    metadata = {"render_modes": ["rgb_array"], "render_fps": 20}

    def __init__(self, task: str | Task | None = None, namespace: str = "/", *,
                 action_mode: str = "reference", use_task_id_obs: bool = True,
                 domain_id: int | None = None, timeout: float = 10.0, render_mode: str | None = None,
                 render_camera: str = "frontview", render_width: int = 256, render_height: int = 256):
        check_action_mode(action_mode)
        if render_mode not in (None, *self.metadata["render_modes"]):
            raise ValueError(f"render_mode {render_mode!r}: use None or one of {self.metadata['render_modes']}")
        self.render_mode = render_mode
        self.render_camera = render_camera
        self.render_size = (render_width, render_height)
        self._drawer = ObservationDrawer(render_camera, render_width, render_height) if render_mode else None
        self._last_observation: ObservationView | None = None
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
        self._last_observation = _view(reply.observation)
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
        if not self._participant.take_for(self._channel.step_awaited, self._channel.timeout,
                                          self._channel.step_subscriptions()):
            raise self._channel.step_lost_error()
        messages = self._channel.take_step()
        self._last_observation = _view(messages.observation)
        info = self._tracker.step_info(messages)
        status = messages.status
        return (flat_observation(messages.observation, self.use_task_id_obs),
                float(messages.reward.total), bool(status.terminated), bool(status.truncated), info)

    def render(self):
        """The scene of the last observation as a `(height, width, 3)` uint8 array with
        `render_mode="rgb_array"`; None without a render mode (Gymnasium's convention)."""
        if self._drawer is None:
            return None
        return self._drawer.draw(self._last_observation)

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
        self.action_space = absolute_action_space(limits)

    def _send(self, action) -> None:
        values = np.asarray(action, dtype=np.float64).reshape(-1)
        check_action(values, self.action_mode)
        if self.action_mode == "reference":
            self._channel.send_reference_action(values)
        else:
            self._channel.send_joint_targets(self._joint_names, values[:ARM_JOINTS + 1])
