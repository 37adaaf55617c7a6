"""Gymnasium steps/s of the composuite_ros package through rclpy (ROS 2 Jazzy, Fast DDS): one
`CompoSuiteRosEnv`, then `CompoSuiteRosVectorEnv` over 2 and 4 environments of
`composuite launch --envs N` (aggregate steps/s: every environment steps once per vector step).

Random reference actions, the suite's horizon of 500 (the env resets itself, the vector env
autoresets); resets are inside the timing. Figures only, nothing is asserted. Run through
`scripts/bench-gym`, which builds the release binaries and enters the loopback-only namespace.

    python tests/py/bench_gym.py --steps 3000 --envs 1 2 4
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import tempfile
import time
from pathlib import Path

import numpy as np

import node_suite
from node_suite import cpu_seconds, node_processes
from composuite_ros import CompoSuiteRosEnv
from composuite_ros.vector import CompoSuiteRosVectorEnv

TASK = "IIWA/box/no_obstacle/pick_place"
ROLES = ("sim", "reward", "task_manager")


def cpu_by_role(namespace: str) -> dict[str, float]:
    """CPU seconds so far of this process (the agent) and of the suite's nodes, summed per kind."""
    times = os.times()
    out = {"agent": times.user + times.system}
    for role in ROLES:
        out[role] = sum(cpu_seconds(pid) for pid in node_processes(f"__ns:={namespace}", role))
    return out


def bench(n: int, steps: int, task: str) -> dict:
    folder = Path(tempfile.mkdtemp(prefix="bench_gym_"))
    extra = ["--envs", str(n)] if n > 1 else []
    rng = np.random.default_rng(0)
    latencies = []
    with node_suite.launch_running(folder, "/bench", task, *extra, service_mapping="fastdds") as launched:
        if n == 1:
            env = CompoSuiteRosEnv(task, "/bench")
            env.reset(seed=0)
            cpu_before = cpu_by_role("/bench")
            started = time.perf_counter()
            for _ in range(steps):
                t = time.perf_counter()
                _, _, terminated, truncated, _ = env.step(rng.uniform(-1, 1, 8))
                if terminated or truncated:
                    env.reset()
                latencies.append(time.perf_counter() - t)
        else:
            env = CompoSuiteRosVectorEnv(launched.namespaces, task)
            env.reset(seed=0)
            cpu_before = cpu_by_role("/bench")
            started = time.perf_counter()
            for _ in range(steps // n):
                t = time.perf_counter()
                env.step(rng.uniform(-1, 1, (n, 8)))
                latencies.append(time.perf_counter() - t)
        elapsed = time.perf_counter() - started
        cpu_after = cpu_by_role("/bench")
        env.close()
    done = len(latencies) * n
    # CPU time per env step of each role (nodes summed over the environments): where a step's
    # cost goes when the cores are full.
    cpu_ms = {role: round((cpu_after[role] - cpu_before[role]) / done * 1e3, 3) for role in cpu_after}
    return {"envs": n, "steps": done, "seconds": round(elapsed, 2), "cpu_ms_per_step": cpu_ms,
            "steps_per_s": round(done / elapsed, 1),
            "step_latency_ms_median": round(statistics.median(latencies) * 1e3, 3),
            "step_latency_ms_p99": round(sorted(latencies)[int(0.99 * (len(latencies) - 1))] * 1e3, 3)}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--steps", type=int, default=3000, help="environment steps per configuration (summed over envs)")
    parser.add_argument("--envs", type=int, nargs="+", default=[1, 2, 4], help="environment counts to measure")
    parser.add_argument("--task", default=TASK)
    parser.add_argument("--json", action="store_true", help="print JSON lines instead of a table")
    args = parser.parse_args()
    node_suite.require_isolation()
    if not args.json:
        print(f"{'envs':>4} {'steps':>7} {'steps/s':>9} {'step ms (median)':>17} {'p99':>8}   "
              "CPU ms per env step: agent / sim / reward / task_manager")
    for n in args.envs:
        r = bench(n, args.steps, args.task)
        if args.json:
            print(json.dumps(r), flush=True)
        else:
            print(f"{r['envs']:>4} {r['steps']:>7} {r['steps_per_s']:>9,.0f} "
                  f"{r['step_latency_ms_median']:>17.3f} {r['step_latency_ms_p99']:>8.3f}   "
                  + " / ".join(f"{r['cpu_ms_per_step'][k]:.2f}" for k in ("agent", *ROLES)), flush=True)


if __name__ == "__main__":
    main()
