"""Benchmark of the sim's ros2_control interfaces with real rclpy (Jazzy, Fast DDS), release
nodes, one environment in lockstep:

- lockstep env steps/s driving through `forward_position_controller/commands` and through
  `joint_command`, alternating in blocks within the same run (so both see the same machine);
  a step = publish the command, wait for that step's observation;
- the FollowJointTrajectory round trip for a 1 s trajectory (20 waypoints 50 ms apart): from
  `send_goal_async` to the result, the goal advancing the sim itself (20 steps).

Run inside the loopback-only namespace with the colcon-built interfaces sourced;
`scripts/bench-controllers` does all that. Figures only — nothing is asserted.

    python tests/py/bench_controllers.py --blocks 6 --block-steps 400 --goals 30
"""

from __future__ import annotations

import argparse
import math
import statistics
import sys
import tempfile
import time

from builtin_interfaces.msg import Duration
from composuite_msgs.msg import Observation
from composuite_msgs.srv import Reset
from control_msgs.action import FollowJointTrajectory
from rclpy.action import ActionClient
from sensor_msgs.msg import JointState
from std_msgs.msg import Float64MultiArray
from trajectory_msgs.msg import JointTrajectoryPoint

import node_suite
from rclpy_agent import RclpyAgent

NS = "/bench"
PERIOD_NS = 50_000_000
HORIZON = 500


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--blocks", type=int, default=6, help="blocks per interface (alternating)")
    parser.add_argument("--block-steps", type=int, default=400, help="lockstep steps per block (< 500)")
    parser.add_argument("--goals", type=int, default=30, help="1 s trajectory goals to time")
    args = parser.parse_args()
    if not 0 < args.block_steps < HORIZON:
        parser.error(f"--block-steps must be in 1..{HORIZON - 1} (one episode per block)")
    domain = node_suite.random_domain()
    with tempfile.TemporaryDirectory() as logs, node_suite.running(logs, NS, domain) as suite:
        agent = RclpyAgent(domain)
        try:
            run(agent, args)
        finally:
            agent.close()
            suite.assert_running()


def run(agent: RclpyAgent, args) -> None:
    node = agent.node
    observations: dict[tuple[int, int], Observation] = {}
    states: list[JointState] = []
    node.create_subscription(Observation, f"{NS}/observation",
                             lambda m: observations.__setitem__((m.episode, m.step), m), 100)
    node.create_subscription(JointState, f"{NS}/joint_states", states.append, 100)
    joint_command = node.create_publisher(JointState, f"{NS}/joint_command", 10)
    forward = node.create_publisher(Float64MultiArray, f"{NS}/forward_position_controller/commands", 10)
    reset_client = node.create_client(Reset, f"{NS}/reset")
    trajectory = ActionClient(node, FollowJointTrajectory,
                              f"{NS}/joint_trajectory_controller/follow_joint_trajectory")
    assert trajectory.wait_for_server(timeout_sec=20.0)
    agent.spin_until(lambda: joint_command.get_subscription_count() and forward.get_subscription_count()
                     and node.count_publishers(f"{NS}/observation"), what="the sim's endpoints")

    def reset(seed: int):
        reply = agent.call(reset_client, Reset.Request(seed=seed, use_seed=True))
        assert reply.success, reply.message
        stamp = reply.observation.header.stamp
        state = agent.spin_until(lambda: next((s for s in states if s.header.stamp == stamp), None),
                                 what="joint_states of the reset")
        states.clear()
        return reply.episode, [n for n in state.name if not n.endswith("finger_joint")], list(state.position[:7])

    def targets(start, k):
        return [q + 0.1 * math.sin(0.05 * k + j) for j, q in enumerate(start)]

    def block(send, seed: int) -> float:
        episode, names, start = reset(seed)
        began = time.perf_counter()
        for k in range(1, args.block_steps + 1):
            send(names, targets(start, k))
            agent.spin_until(lambda: (episode, k) in observations, what=f"observation {k}")
        elapsed = time.perf_counter() - began
        observations.clear()
        return args.block_steps / elapsed

    by_joint_command = lambda names, t: joint_command.publish(JointState(name=names, position=t))  # noqa: E731
    by_forward = lambda names, t: forward.publish(Float64MultiArray(data=t))  # noqa: E731
    block(by_joint_command, 0)  # warm-up: every endpoint matched, caches warm
    rates = {"joint_command": [], "forward_position_controller/commands": []}
    for b in range(args.blocks):
        rates["joint_command"].append(block(by_joint_command, b + 1))
        rates["forward_position_controller/commands"].append(block(by_forward, b + 1))
    print(f"lockstep steps/s over {args.blocks} blocks of {args.block_steps} steps (alternating):")
    for name, values in rates.items():
        print(f"  {name:40s} median {statistics.median(values):6.0f}  min {min(values):6.0f}  "
              f"max {max(values):6.0f}")

    times = []
    for g in range(args.goals):
        episode, names, start = reset(100 + g)
        goal = FollowJointTrajectory.Goal()
        goal.trajectory.joint_names = names
        for k in range(1, 21):
            t = k * PERIOD_NS
            goal.trajectory.points.append(JointTrajectoryPoint(
                positions=targets(start, k), time_from_start=Duration(sec=t // 10**9, nanosec=t % 10**9)))
        began = time.perf_counter()
        sent = trajectory.send_goal_async(goal)
        agent.spin_until(sent.done, what="the goal response")
        handle = sent.result()
        assert handle.accepted
        result = handle.get_result_async()
        agent.spin_until(result.done, what="the result")
        times.append(time.perf_counter() - began)
        assert result.result().result.error_code == 0, result.result().result.error_string
    times.sort()
    print(f"FollowJointTrajectory round trip, 1 s trajectory (20 lockstep steps), {args.goals} goals:")
    print(f"  median {statistics.median(times) * 1e3:.1f} ms  p90 {times[int(0.9 * (len(times) - 1))] * 1e3:.1f} ms  "
          f"min {times[0] * 1e3:.1f} ms")


if __name__ == "__main__":
    sys.exit(main())
