"""Speed of the standard simulation interfaces on one environment, with real rclpy (Jazzy,
Fast DDS) as the client: `step_simulation` calls per second (one step each, a reply per call),
one `step_simulation` of 1,000 steps, and one 1,000-step `simulate_steps` goal (feedback per
step). For the bursts it also counts the rewards and episode statuses that arrived for their
steps (an agent-side reader keeping 2,000 messages): every step's messages are published, and
this says whether they all got through.

Run inside the loopback-only namespace, with the node binaries of $COMPOSUITE_NODE_DIR (as the
tests; the release build: `cargo build --release -p composuite_ros --bins` and
COMPOSUITE_NODE_DIR=$CARGO_TARGET_DIR/release). Figures only — nothing is asserted.

    scripts/netns-isolate python tests/py/bench_simulation_interfaces.py --calls 500
"""

from __future__ import annotations

import argparse
import tempfile
import time
from pathlib import Path

from composuite_msgs.msg import EpisodeStatus, StagedReward
from rclpy.action import ActionClient
from rclpy.qos import QoSProfile, ReliabilityPolicy
from simulation_interfaces.action import SimulateSteps
from simulation_interfaces.msg import Result
from simulation_interfaces.srv import ResetSimulation, StepSimulation

import node_suite
from rclpy_agent import RclpyAgent

NS = "/bench_si"
DEEP = QoSProfile(depth=2000, reliability=ReliabilityPolicy.RELIABLE)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--calls", type=int, default=500, help="step_simulation calls of one step")
    parser.add_argument("--burst", type=int, default=1000, help="steps of the burst figures")
    args = parser.parse_args()
    node_suite.require_isolation()
    domain = node_suite.random_domain()
    horizon = args.calls + 2 * args.burst + 10  # one episode holds every step of the run
    with tempfile.TemporaryDirectory() as logs, node_suite.running(
            Path(logs), NS, domain, task_manager={"horizon": horizon}) as suite:
        agent = RclpyAgent(domain)
        node = agent.node
        rewards, statuses = set(), set()
        node.create_subscription(StagedReward, f"{NS}/reward", lambda m: rewards.add((m.episode, m.step)), DEEP)
        node.create_subscription(EpisodeStatus, f"{NS}/episode",
                                 lambda m: statuses.add((m.episode, m.step)), DEEP)
        step = node.create_client(StepSimulation, f"{NS}/step_simulation")
        reset = node.create_client(ResetSimulation, f"{NS}/reset_simulation")
        steps = ActionClient(node, SimulateSteps, f"{NS}/simulate_steps", feedback_sub_qos_profile=DEEP)
        # A refused call first: this client's replies are matched, so the rest are sent once.
        assert agent.call(step, StepSimulation.Request(steps=0)).result.result == Result.RESULT_OPERATION_FAILED
        assert agent.call(reset, ResetSimulation.Request()).result.result == Result.RESULT_OK
        agent.spin_until(lambda: node.count_publishers(f"{NS}/reward") >= 1, what="the reward writer")
        episode = None

        started = time.perf_counter()
        for _ in range(args.calls):
            reply = agent.call(step, StepSimulation.Request(steps=1), attempt=10.0)
            assert reply.result.result == Result.RESULT_OK, reply.result.error_message
        elapsed = time.perf_counter() - started
        print(f"step_simulation, 1 step per call: {args.calls / elapsed:.0f} calls/s "
              f"({elapsed / args.calls * 1e3:.2f} ms per call, {args.calls} calls)")
        agent.spin_until(lambda: rewards, what="a reward")
        episode = max(e for e, _ in rewards)
        done_steps = args.calls

        def arrived(first: int, last: int) -> str:
            # Give stragglers 2 s, then count.
            deadline = time.monotonic() + 2.0
            want = {(episode, k) for k in range(first, last + 1)}
            while time.monotonic() < deadline and not (want <= rewards and want <= statuses):
                agent.executor.spin_once(timeout_sec=0.05)
            return (f"rewards {len(want & rewards)}/{len(want)}, "
                    f"episode statuses {len(want & statuses)}/{len(want)} arrived")

        started = time.perf_counter()
        reply = agent.call(step, StepSimulation.Request(steps=args.burst), timeout=600.0, attempt=600.0)
        elapsed = time.perf_counter() - started
        assert reply.result.result == Result.RESULT_OK, reply.result.error_message
        print(f"step_simulation of {args.burst} steps: {elapsed:.3f} s "
              f"({args.burst / elapsed:.0f} steps/s); "
              f"{arrived(done_steps + 1, done_steps + args.burst)}")
        done_steps += args.burst

        assert steps.wait_for_server(timeout_sec=10.0)
        feedback = []
        started = time.perf_counter()
        goal = steps.send_goal_async(SimulateSteps.Goal(steps=args.burst),
                                     feedback_callback=lambda f: feedback.append(f.feedback.completed_steps))
        handle = agent.spin_until(lambda: goal.done() and goal.result(), what="the goal response")
        agent.spin_until(lambda: len(feedback) == args.burst or (feedback and feedback[-1] == args.burst),
                         timeout=600.0, what="the last feedback")
        result = handle.get_result_async()
        outcome = agent.spin_until(lambda: result.done() and result.result(), timeout=60.0, what="the result")
        elapsed = time.perf_counter() - started
        assert outcome.result.result.result == Result.RESULT_OK, outcome.result.result.error_message
        print(f"simulate_steps goal of {args.burst} steps (accept to result): {elapsed:.3f} s "
              f"({args.burst / elapsed:.0f} steps/s); feedback {len(feedback)}/{args.burst}; "
              f"{arrived(done_steps + 1, done_steps + args.burst)}")
        agent.close()
        jumps = suite.stderr("task_manager").count("jumped")
        print(f"task_manager: {jumps} 'world_state jumped' warnings (a lost step)")


if __name__ == "__main__":
    main()
