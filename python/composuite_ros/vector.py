"""`CompoSuiteRosVectorEnv`: N environments of the suite stepped concurrently, as a Gymnasium 1.x
`VectorEnv` (next-step autoreset).

    composuite launch --envs 4 --task IIWA/box/no_obstacle/pick_place &     # /env_00 ... /env_03

    from composuite_ros.vector import CompoSuiteRosVectorEnv
    envs = CompoSuiteRosVectorEnv(
        namespaces=["/env_00", "/env_01", "/env_02", "/env_03"],
        tasks=["IIWA/box/no_obstacle/pick_place", "Jaco/plate/object_wall/shelf"] * 2)
    observations, infos = envs.reset(seed=0)
    observations, rewards, terminations, truncations, infos = envs.step(envs.action_space.sample())

A step publishes every environment's action first, then gathers every environment's step: the
environments (separate sim processes, on this machine or others) work in parallel. One rclpy
participant serves them all. Environments on other machines are just other namespaces on the
same ROS_DOMAIN_ID: DDS discovery finds them (docs/src/many-machines.md).

Autoreset (Gymnasium's NEXT_STEP mode): when environment i ends an episode, the next `step()`
ignores its action, resets it (the next seed of its own sequence) and returns the new episode's
first observation with reward 0 and terminated = truncated = False.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
from gymnasium.vector import VectorEnv
from gymnasium.vector.utils import batch_space

from ._gymnasium import NEXT_STEP_AUTORESET
from ._link import Channel, Participant, attempt_budget
from .env import (EpisodeSeeds, EpisodeTracker, ObservationDrawer, flat_observation, observation_space,
                  reference_action_space, stamp_ns)
from .episode import vector_seeds
from .errors import EpisodeOverError
from .tasks import Task


class CompoSuiteRosVectorEnv(VectorEnv):
    """Environments in `namespaces` (one per sub-environment), each set to its task.

    Args:
        namespaces: one namespace per environment (`composuite launch --envs N` makes
            `/env_00` ... ; with a `--namespace` base, `<base>/env_00` ...).
        tasks: one task for all, or one per environment (None: keep each suite's task).
        use_task_id_obs: 93-value observations with the task one-hots (True) or 77.
        domain_id: ROS_DOMAIN_ID (default: the environment variable, else 0).
        timeout: seconds any wait may take before it raises, naming what it waited for (the
            first contact with the suite, discovery, may take 3 times as long).
        render_mode, render_camera, render_width, render_height: as `CompoSuiteRosEnv`;
            `render()` returns a tuple with each environment's last observation drawn.

    Actions are the reference benchmark's (8 values in [-1, 1] per environment).
    """

    metadata = {**NEXT_STEP_AUTORESET, "render_modes": ["rgb_array"], "render_fps": 20}

    def __init__(self, namespaces: Sequence[str], tasks: str | Task | Sequence[str | Task] | None = None,
                 *, use_task_id_obs: bool = True, domain_id: int | None = None, timeout: float = 10.0,
                 render_mode: str | None = None, render_camera: str = "frontview", render_width: int = 256,
                 render_height: int = 256):
        if render_mode not in (None, *self.metadata["render_modes"]):
            raise ValueError(f"render_mode {render_mode!r}: use None or one of {self.metadata['render_modes']}")
        self.render_mode = render_mode
        self._drawer = ObservationDrawer(render_camera, render_width, render_height) if render_mode else None
        if not namespaces:
            raise ValueError("namespaces is empty: give one namespace per environment")
        if len(set(namespaces)) != len(namespaces):
            raise ValueError(f"namespaces repeat: {list(namespaces)}; each environment needs its own")
        self.num_envs = len(namespaces)
        if tasks is None or isinstance(tasks, (str, Task)):
            tasks = [tasks] * self.num_envs
        if len(tasks) != self.num_envs:
            raise ValueError(f"{len(tasks)} tasks for {self.num_envs} namespaces; give one task or one per namespace")
        self.use_task_id_obs = use_task_id_obs
        self.single_observation_space = observation_space(use_task_id_obs)
        self.single_action_space = reference_action_space()
        self.observation_space = batch_space(self.single_observation_space, self.num_envs)
        self.action_space = batch_space(self.single_action_space, self.num_envs)
        self._seeds = [EpisodeSeeds() for _ in range(self.num_envs)]
        self._trackers: list[EpisodeTracker | None] = [None] * self.num_envs
        self._autoreset = np.zeros(self.num_envs, dtype=bool)
        self._last_observations: list = [None] * self.num_envs
        self._participant = Participant("composuite_gym_vector", domain_id)
        try:
            self.channels = [Channel(self._participant, ns, timeout) for ns in namespaces]
            self.timeout = timeout
            self.wait_ready()
            self.tasks: list[Task | None] = [None] * self.num_envs
            for i, task in enumerate(tasks):
                if task is not None:
                    self.set_task(i, task)
        except BaseException:
            self._participant.close()
            raise

    @property
    def namespaces(self) -> list[str]:
        return [c.namespace for c in self.channels]

    def wait_ready(self) -> None:
        """Until every environment's topics and services are matched."""
        seconds = self.channels[0].discovery_timeout
        if not self._participant.spin_for(lambda: not any(c.missing() for c in self.channels), seconds):
            raise next(c for c in self.channels if c.missing()).not_running_error(
                "waiting for the suite's topics and services", seconds)

    def set_task(self, index: int, task: str | Task) -> Task:
        """Give environment `index` a task (its episode ends; the next reset starts the new one)."""
        self.tasks[index] = self.channels[index].set_task(Task.parse(task))
        self._trackers[index] = None
        return self.tasks[index]

    # ---- resets -------------------------------------------------------------------------------

    def _reset_many(self, indices: list[int], seeds: list[int | None]) -> dict[int, object]:
        """Reset the environments at `indices` concurrently; their reset replies by index."""
        replies: dict[int, object] = {}
        episode_seeds = {i: self._seeds[i].next(seed) for i, seed in zip(indices, seeds)}
        pending = {i: self.channels[i].start_reset(episode_seeds[i]) for i in indices}
        self._participant.spin_for(lambda: all(f.done() for f in pending.values()), attempt_budget(0))
        for i, future in pending.items():
            channel = self.channels[i]
            if future.done():
                replies[i] = channel.finish_reset(future)
                if not channel.await_step0():
                    # The sim's writer does not know this reader yet: the careful path.
                    replies[i] = channel.reset(episode_seeds[i])
            else:
                # Slow or lost (discovery still settling): the careful one-by-one path, same seed.
                channel.reset_client.remove_pending_request(future)
                replies[i] = channel.reset(episode_seeds[i])
        for i in indices:
            self._trackers[i] = EpisodeTracker(stamp_ns(replies[i].observation))
            self._last_observations[i] = replies[i].observation
        return replies

    def reset(self, *, seed: int | list[int | None] | None = None, options: dict | None = None):
        """Reset every environment. `seed`: an int s gives environment i the seed s + i (as
        Gymnasium's own vector envs do), a list one seed per environment."""
        seeds = vector_seeds(seed, self.num_envs)
        if options and "tasks" in options:
            for i, task in enumerate(options["tasks"]):
                self.set_task(i, task)
        self.wait_ready()
        replies = self._reset_many(list(range(self.num_envs)), seeds)
        self._autoreset[:] = False
        observations = np.stack([flat_observation(replies[i].observation, self.use_task_id_obs)
                                 for i in range(self.num_envs)])
        infos: dict = {}
        for i in range(self.num_envs):
            infos = self._add_info(infos, self._reset_info(i, replies[i]), i)
        return observations, infos

    def _reset_info(self, i: int, reply) -> dict:
        return {"episode": int(reply.episode), "seed": int(reply.seed), "task": str(self.tasks[i] or ""),
                "sim_time": 0.0, "suite_time": stamp_ns(reply.observation) * 1e-9}

    # ---- steps --------------------------------------------------------------------------------

    def step(self, actions):
        actions = np.asarray(actions, dtype=np.float64)
        if actions.shape != (self.num_envs, 8):
            raise ValueError(f"actions have shape {actions.shape}; expected ({self.num_envs}, 8): "
                             "per environment 7 joint deltas and the gripper, each in [-1, 1]")
        if not np.all(np.isfinite(actions)):
            raise ValueError("actions have non-finite values")
        stepping = [i for i in range(self.num_envs) if not self._autoreset[i]]
        resetting = [i for i in range(self.num_envs) if self._autoreset[i]]
        for i in stepping:
            if self._trackers[i] is None:
                raise EpisodeOverError(f"environment {i} ({self.channels[i].namespace}) has no "
                                       "episode: call reset() first")
            self.channels[i].send_reference_action(actions[i])
        replies = self._reset_many(resetting, [None] * len(resetting)) if resetting else {}
        waiting = [self.channels[i] for i in stepping]

        def awaited() -> list:
            # Channels whose step is complete leave for good; the others name what they lack.
            nonlocal waiting
            subs = []
            still = []
            for channel in waiting:
                lacking = channel.step_awaited()
                if lacking:
                    still.append(channel)
                    subs.extend(lacking)
            waiting = still
            return subs

        arrived = self._participant.take_for(
            awaited, self.timeout,
            [sub for i in stepping for sub in self.channels[i].step_subscriptions()])
        if not arrived:
            raise next(self.channels[i] for i in stepping
                       if not self.channels[i].step_arrived()).step_lost_error()
        observations = np.empty((self.num_envs, self.single_observation_space.shape[0]))
        rewards = np.zeros(self.num_envs)
        terminations = np.zeros(self.num_envs, dtype=bool)
        truncations = np.zeros(self.num_envs, dtype=bool)
        infos: dict = {}
        for i in stepping:
            messages = self.channels[i].take_step()
            self._last_observations[i] = messages.observation
            observations[i] = flat_observation(messages.observation, self.use_task_id_obs)
            rewards[i] = messages.reward.total
            terminations[i] = messages.status.terminated
            truncations[i] = messages.status.truncated
            infos = self._add_info(infos, self._trackers[i].step_info(messages), i)
        for i in resetting:
            observations[i] = flat_observation(replies[i].observation, self.use_task_id_obs)
            infos = self._add_info(infos, self._reset_info(i, replies[i]), i)
        self._autoreset = terminations | truncations
        return observations, rewards, terminations, truncations, infos

    def render(self) -> tuple[np.ndarray, ...] | None:
        """Each environment's last observation drawn, a tuple of `(height, width, 3)` uint8 arrays
        in environment order, with `render_mode="rgb_array"`; None without a render mode."""
        if self._drawer is None:
            return None
        return tuple(self._drawer.draw(o) for o in self._last_observations)

    def close_extras(self, **kwargs) -> None:
        """Leave the ROS graph: no node, participant or thread of these envs remains."""
        self._participant.close()
