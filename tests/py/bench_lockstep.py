"""Lockstep benchmark of the node suite with a Python cyclonedds agent (what rmw_cyclonedds puts
on the wire), for the reference benchmark's four tasks.

An agent step is what an RL loop does: publish `joint_command`, then wait for the observation
AND the reward of that step (matched by episode and step, never "the latest"). Per task: launch
the suite (`composuite launch --service-mapping cyclone`), reset through the service, run the
steps (reset every 500 = the horizon), print env steps/s and the step latency median and p99.

With `--camera NAME`, the sim also publishes that camera's images (`--camera-size`, 84 by
default) and an agent step waits for the step's image as well: the cost of one camera on.
`--camera-unread` turns the camera on without subscribing to it: the sim renders every step,
but no reader means nothing is sent — the cost of the drawing alone.

Run inside the loopback-only namespace; `scripts/bench-ros` does that and builds the release
binaries first. Figures only — nothing is asserted.

    python tests/py/bench_lockstep.py --composuite target/release/composuite --steps 2000
    python tests/py/bench_lockstep.py --composuite target/release/composuite --camera frontview
"""

from __future__ import annotations

import argparse
import json
import os
import random
import signal
import statistics
import subprocess
import sys
import threading
import time

import node_suite
import ros_agent

REFERENCE_TASKS = [
    "IIWA/box/no_obstacle/pick_place",
    "Jaco/dumbbell/object_door/shelf",
    "Panda/plate/goal_wall/trash_can",
    "Gen3/hollow_box/object_wall/push",
]
ARM_JOINTS = 7
WAIT_FOR_REWARD = os.environ.get("BENCH_OBSERVATION_ONLY") != "1"


class RssSampler:
    """Every `every` s, one stderr line with the agent steps done and the resident memory of each
    node the launcher started (a soak: `--steps 1000000 --rss-every 60`)."""

    def __init__(self, launcher_pid: int, every: float, steps_done):
        self.launcher_pid, self.every, self.steps_done = launcher_pid, every, steps_done
        self.started = time.monotonic()
        self._stop = threading.Event()
        self._thread = threading.Thread(target=self._run, daemon=True)
        self._thread.start()

    def _nodes(self) -> dict[str, int]:
        """{node kind: RSS kB} of the launcher's children (`composuite node KIND ...`)."""
        out = {}
        try:
            children = open(f"/proc/{self.launcher_pid}/task/{self.launcher_pid}/children").read().split()
        except OSError:
            return out
        for pid in children:
            try:
                args = open(f"/proc/{pid}/cmdline", "rb").read().split(b"\0")
                rss = next(line for line in open(f"/proc/{pid}/status") if line.startswith("VmRSS"))
            except (OSError, StopIteration):
                continue
            kind = args[2].decode() if len(args) > 2 else pid
            out[kind] = int(rss.split()[1])
        return out

    def _run(self) -> None:
        while not self._stop.wait(self.every):
            nodes = " ".join(f"{k} {v / 1024:.1f} MB" for k, v in sorted(self._nodes().items()))
            print(f"rss: {time.monotonic() - self.started:7.0f} s  {self.steps_done():9d} steps  {nodes}",
                  file=sys.stderr, flush=True)

    def stop(self) -> None:
        self._stop.set()
        self._thread.join()


def camera_params(camera: str, size: int) -> list[str]:
    """`--params-file` arguments that turn on one camera of the sim (none without a camera)."""
    if not camera:
        return []
    path = f"/tmp/bench_lockstep_camera_{os.getpid()}.yaml"
    with open(path, "w") as f:
        f.write(f"/**/sim:\n  ros__parameters:\n    cameras: [{camera}]\n"
                f"    camera_width: {size}\n    camera_height: {size}\n")
    return ["--params-file", path]


def bench_task(composuite: str, task: str, steps: int, horizon: int, rss_every: float = 0.0,
               camera: str = "", camera_size: int = 84, camera_read: bool = True) -> dict:
    domain = node_suite.random_domain()
    env = dict(os.environ, ROS_DOMAIN_ID=str(domain))
    failed = False
    suite = subprocess.Popen(
        [*node_suite.suite_launcher(), composuite, "launch", "--task", task, "--service-mapping", "cyclone",
         "--horizon", str(horizon), "--namespace", "/bench", "--log-level", os.environ.get("BENCH_LOG_LEVEL", "warn"),
         *camera_params(camera, camera_size)],
        env=env, stderr=subprocess.PIPE, text=True)
    try:
        with ros_agent.Agent(namespace="/bench", domain_id=domain) as agent:
            images = (agent.subscribe(f"camera/{camera}/image_raw", "sensor_msgs/msg/Image")
                      if camera and camera_read else None)
            states = agent.subscribe("joint_states", "sensor_msgs/msg/JointState")
            observations = agent.subscribe("observation", "composuite_msgs/msg/Observation")
            rewards = agent.subscribe("reward", "composuite_msgs/msg/StagedReward")
            command = agent.publisher("joint_command", "sensor_msgs/msg/JointState")
            reset = agent.service_client("reset", "composuite_msgs/srv/Reset", format="cyclone")
            reset.wait_for_service(timeout=20)
            command.wait_for_subscribers(1, timeout=20)
            observations.wait_for_publishers(timeout=20)
            rewards.wait_for_publishers(timeout=20)
            if images:
                images.wait_for_publishers(timeout=20)
            _, first = ros_agent.reset_with_joint_states(reset, states, seed=0)
            done = 0
            sampler = RssSampler(suite.pid, rss_every, lambda: done) if rss_every else None
            names = list(first.name[:ARM_JOINTS])
            home = list(first.position[:ARM_JOINTS])
            rng = random.Random(7)
            latencies: list[float] = []
            reset_times: list[float] = []
            t_start = time.perf_counter()
            while done < steps:
                t0 = time.perf_counter()
                reply = reset.call({"seed": done // horizon, "use_seed": True}, timeout=10)
                reset_times.append(time.perf_counter() - t0)
                assert reply.success, reply.message
                episode = reply.episode
                for k in range(1, min(horizon, steps - done) + 1):
                    targets = [q + rng.uniform(-0.05, 0.05) for q in home]
                    o_start, r_start = len(observations.samples), len(rewards.samples)
                    i_start = len(images.samples) if images else 0
                    t0 = time.perf_counter()
                    command.publish(name=names, position=targets)
                    seen = observations.wait_for({"episode": episode, "step": k}, timeout=5, start=o_start)
                    if images:
                        images.wait_for({"header.stamp.sec": seen.header.stamp.sec,
                                         "header.stamp.nanosec": seen.header.stamp.nanosec},
                                        timeout=5, start=i_start)
                    if WAIT_FOR_REWARD:
                        rewards.wait_for({"episode": episode, "step": k}, timeout=5, start=r_start)
                    latencies.append(time.perf_counter() - t0)
                    done += 1
                # Keep memory flat over long runs.
                observations.clear()
                rewards.clear()
                states.clear()
                if images:
                    images.clear()
            wall = time.perf_counter() - t_start
            if sampler:
                sampler.stop()
    except BaseException:
        failed = True
        raise
    finally:
        suite.send_signal(signal.SIGINT)
        try:
            _, err = suite.communicate(timeout=10)
        except subprocess.TimeoutExpired:
            suite.kill()
            _, err = suite.communicate()
        if suite.returncode != 0 or failed:
            print(f"launch exited {suite.returncode}: {err[-3000:]}", file=sys.stderr)
        # With BENCH_LOG_LEVEL=debug the sim reports where its step time goes.
        for line in err.splitlines():
            if "steps: physics" in line:
                print(line, file=sys.stderr)
    latencies.sort()
    return {
        "task": task,
        "steps": len(latencies),
        "steps_per_s": len(latencies) / sum(latencies),
        "wall_steps_per_s": len(latencies) / wall,
        "median_ms": statistics.median(latencies) * 1e3,
        "p99_ms": latencies[int(0.99 * (len(latencies) - 1))] * 1e3,
        "reset_ms": statistics.median(reset_times) * 1e3,
    }


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--composuite", required=True, help="path of the (release) composuite binary")
    parser.add_argument("--steps", type=int, default=2000, help="agent steps per task")
    parser.add_argument("--horizon", type=int, default=500, help="steps per episode")
    parser.add_argument("--tasks", nargs="*", default=REFERENCE_TASKS)
    parser.add_argument("--json", action="store_true", help="print JSON instead of a table")
    parser.add_argument("--rss-every", type=float, default=0.0, metavar="SECONDS",
                        help="soak: print the nodes' resident memory every SECONDS (stderr)")
    parser.add_argument("--camera", default="", help="turn this camera's image topic on and wait for its images")
    parser.add_argument("--camera-size", type=int, default=84, help="the camera's width and height (pixels)")
    parser.add_argument("--camera-unread", action="store_true",
                        help="turn the camera on but do not subscribe to it (the drawing's cost alone)")
    args = parser.parse_args()
    results = []
    for task in args.tasks:
        print(f"bench: {task} ...", file=sys.stderr, flush=True)
        results.append(bench_task(args.composuite, task, args.steps, args.horizon, args.rss_every,
                                  args.camera, args.camera_size, not args.camera_unread))
    if args.json:
        print(json.dumps(results, indent=1))
        return
    print(f"{'task':<36} {'steps/s':>8} {'(wall)':>8} {'median ms':>10} {'p99 ms':>8} {'reset ms':>9}")
    for r in results:
        print(f"{r['task']:<36} {r['steps_per_s']:>8.0f} {r['wall_steps_per_s']:>8.0f} "
              f"{r['median_ms']:>10.3f} {r['p99_ms']:>8.3f} {r['reset_ms']:>9.2f}")


if __name__ == "__main__":
    main()
