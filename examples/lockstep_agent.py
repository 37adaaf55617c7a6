"""A minimal rclpy agent for CompoSuite-ROS in lockstep mode: what an RL environment wrapper
does, in one readable file. ROS 2 Jazzy's rclpy, composuite_msgs built in your workspace.

    composuite launch --task IIWA/box/no_obstacle/pick_place &      # the suite (lockstep)
    python examples/lockstep_agent.py --episodes 2 --steps 100      # random joint targets

The protocol (docs/src/node-suite.md, "Lockstep"): reset through the `reset` service (the reply
carries the step-0 observation); then per step publish `joint_command` (all seven arm joints,
absolute targets) and wait for the `observation`, `reward` and `episode` messages of that step,
matched by (episode, step) — never "the latest message". Every wait has a wall-clock deadline.

rclpy 7.1.6 notes: a private Context, an own SingleThreadedExecutor polled with spin_once (no
spin_until_future_complete on service futures: it slows down with every call in that release).
"""

from __future__ import annotations

import argparse
import math
import random
import time

import rclpy
from composuite_msgs.msg import EpisodeStatus, Observation, StagedReward
from composuite_msgs.srv import Reset
from rclpy.context import Context
from rclpy.executors import SingleThreadedExecutor
from rclpy.node import Node
from rclpy.qos import QoSProfile, ReliabilityPolicy
from sensor_msgs.msg import JointState
from std_msgs.msg import Header

ARM_JOINTS = 7


class LockstepEnv:
    """reset(seed) -> observation; step(targets) -> (observation, reward, terminated, truncated,
    info) — the Gymnasium shapes, over ROS 2."""

    def __init__(self, namespace: str = "/", domain_id: int | None = None, timeout: float = 10.0):
        self.timeout = timeout
        self.context = Context()
        rclpy.init(context=self.context, domain_id=domain_id)
        self.node = Node("lockstep_agent", namespace=namespace, context=self.context,
                         start_parameter_services=False)
        self.executor = SingleThreadedExecutor(context=self.context)
        self.executor.add_node(self.node)
        qos = QoSProfile(depth=10, reliability=ReliabilityPolicy.RELIABLE)
        # Everything received, keyed by (episode, step); earlier episodes' dropped at each reset.
        self.observations: dict[tuple[int, int], Observation] = {}
        self.rewards: dict[tuple[int, int], StagedReward] = {}
        self.statuses: dict[tuple[int, int], EpisodeStatus] = {}
        self.joint_names: list[str] = []
        self.node.create_subscription(Observation, "observation",
                                      lambda m: self.observations.__setitem__((m.episode, m.step), m), qos)
        self.node.create_subscription(StagedReward, "reward",
                                      lambda m: self.rewards.__setitem__((m.episode, m.step), m), qos)
        self.node.create_subscription(EpisodeStatus, "episode",
                                      lambda m: self.statuses.__setitem__((m.episode, m.step), m), qos)
        self.node.create_subscription(JointState, "joint_states", self._on_joint_states, qos)
        self.command = self.node.create_publisher(JointState, "joint_command", qos)
        self.reset_client = self.node.create_client(Reset, "reset")
        self.episode = 0
        self.step_count = 0

    def _on_joint_states(self, message: JointState) -> None:
        if not self.joint_names:
            self.joint_names = list(message.name[:ARM_JOINTS])

    def _spin_until(self, done, what: str) -> None:
        if not self._spin_for(done, self.timeout):
            raise TimeoutError(f"no {what} within {self.timeout} s; is the suite running (lockstep)?")

    def _spin_for(self, done, seconds: float) -> bool:
        """Spin until `done()` or `seconds` passed; whether it is done."""
        deadline = time.monotonic() + seconds
        while not done():
            if time.monotonic() > deadline:
                return False
            self.executor.spin_once(timeout_sec=0.01)
        return True

    def reset(self, seed: int | None = None, attempts: int = 5) -> Observation:
        """Start an episode (`seed`, or the suite's next one) and return its step-0 observation.

        Right after discovery each side learns of the other on its own, so the first reply, or
        a step-0 message, can go out before the suite's writer knows this agent's reader: wait
        for the step-0 observation, reward and episode status (and `joint_states`, for the joint
        names) and ask again if one is missing (a retry without a seed moves on to the next seed)."""
        request = Reset.Request(seed=seed or 0, use_seed=seed is not None)
        for _ in range(attempts):
            self._spin_until(self.reset_client.service_is_ready, "reset service")
            future = self.reset_client.call_async(request)
            if not self._spin_for(future.done, min(self.timeout, 3.0)):
                self.reset_client.remove_pending_request(future)
                continue
            reply = future.result()
            if not reply.success:
                raise RuntimeError(f"reset refused: {reply.message}")
            self.episode, self.step_count = reply.episode, 0
            for store in (self.observations, self.rewards, self.statuses):
                for key in [k for k in store if k[0] != reply.episode]:
                    del store[key]
            key = (reply.episode, 0)
            self.answered = reply.observation.header.stamp  # what the first command answers
            if self._spin_for(lambda: (bool(self.joint_names) and key in self.observations
                                       and key in self.rewards and key in self.statuses), 1.0):
                return reply.observation
        raise TimeoutError(f"no reset reply with joint_states after {attempts} attempts; "
                           "is the suite running (lockstep) in this namespace?")

    def step(self, targets: list[float]):
        key = (self.episode, self.step_count + 1)
        # Stamped with the observation it answers: the sim drops a command meant for an earlier
        # episode (say, sent by an agent that died while another reset).
        self.command.publish(JointState(header=Header(stamp=self.answered), name=self.joint_names,
                                        position=[float(t) for t in targets]))
        self._spin_until(lambda: key in self.observations and key in self.rewards and key in self.statuses,
                         f"observation/reward/episode for step {key[1]}")
        self.step_count += 1
        observation, reward, status = self.observations[key], self.rewards[key], self.statuses[key]
        self.answered = observation.header.stamp
        info = {"success": reward.success, "stages": dict(zip(reward.stage_names, reward.stage_values)),
                "reason": status.reason_text}
        return observation, reward.total, status.terminated, status.truncated, info

    def close(self) -> None:
        self.executor.shutdown()
        self.node.destroy_node()
        rclpy.shutdown(context=self.context)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--namespace", default="/")
    parser.add_argument("--episodes", type=int, default=1)
    parser.add_argument("--steps", type=int, default=100, help="steps per episode at most")
    parser.add_argument("--seed", type=int, default=0)
    args = parser.parse_args()
    env = LockstepEnv(args.namespace)
    rng = random.Random(args.seed)
    try:
        for episode in range(args.episodes):
            observation = env.reset(seed=args.seed + episode)
            # Joint angles from the observation's cos/sin (the factored robot state).
            home = [math.atan2(s, c) for s, c in zip(observation.robot.joint_pos_sin, observation.robot.joint_pos_cos)]
            total, started = 0.0, time.perf_counter()
            for _ in range(args.steps):
                targets = [q + rng.uniform(-0.1, 0.1) for q in home]
                observation, reward, terminated, truncated, info = env.step(targets)
                total += reward
                if terminated or truncated:
                    break
            elapsed = time.perf_counter() - started
            print(f"episode {env.episode}: {env.step_count} steps, return {total:.3f}, "
                  f"{env.step_count / elapsed:.0f} steps/s")
    finally:
        env.close()


if __name__ == "__main__":
    main()
