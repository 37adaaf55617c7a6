"""Speed of the in-process Python environments (composuite_ros.native), printed, asserted nowhere.

    python bench_python.py --composuite PATH [--tasks T ...] [--steps N] [--rounds R] [--json]

1. One `CompoSuiteNativeEnv`, uniform random reference actions (drawn beforehand), a reset every
   500 steps (or when an episode ends), pinned to one core — beside `composuite bench` on the same
   task and core, alternating, median of the rounds. Steps/s counts the time inside `step()`
   only, as `composuite bench` does; "loop" is the whole loop, resets included.
2. `CompoSuiteNativeVectorEnv` of N environments with 1 thread and with 2 (aggregate steps/s
   over the whole loop, autoresets included).

Run by scripts/bench-python, which builds the release `composuite` and installs the package
the way a user does (`pip install ./python`) into its own venv.
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import subprocess
import sys
import time

import numpy as np

REFERENCE_TASKS = ["IIWA/box/no_obstacle/pick_place", "Jaco/dumbbell/object_door/shelf",
                   "Panda/plate/goal_wall/trash_can", "Gen3/hollow_box/object_wall/push"]


def single_env_worker(task: str, steps: int) -> dict:
    """Runs in a child process pinned to one core."""
    from composuite_ros import CompoSuiteNativeEnv
    env = CompoSuiteNativeEnv(task)
    actions = np.random.default_rng(0).uniform(-1, 1, size=(steps, 8))
    env.reset(seed=0)
    for action in actions[:500]:  # warm-up episode
        _, _, terminated, truncated, _ = env.step(action)
        if terminated or truncated:
            break
    env.reset(seed=1)
    seed, in_episode, stepping = 1, 0, 0.0
    start = time.perf_counter()
    for action in actions:
        t = time.perf_counter()
        _, _, terminated, truncated, _ = env.step(action)
        stepping += time.perf_counter() - t
        in_episode += 1
        if terminated or truncated or in_episode == 500:
            seed += 1
            in_episode = 0
            env.reset(seed=seed)
    loop = time.perf_counter() - start
    return {"steps_per_s": steps / stepping, "loop_steps_per_s": steps / loop}


def pinned(cmd: list[str], core: int) -> list[str]:
    return ["taskset", "-c", str(core), *cmd]


def measure_single(args, task: str) -> dict:
    rust, native, loop = [], [], []
    for _ in range(args.rounds):
        out = subprocess.run(pinned([args.composuite, "bench", "--tasks", task, "--steps", str(args.steps),
                                     "--json"], args.core), capture_output=True, text=True, check=True)
        rust.append(json.loads(out.stdout)[0]["steps_per_s"])
        code = (f"import json, bench_python; print(json.dumps(bench_python.single_env_worker("
                f"{task!r}, {args.steps})))")
        out = subprocess.run(pinned([sys.executable, "-c", code], args.core), capture_output=True,
                             text=True, check=True, cwd=os.path.dirname(os.path.abspath(__file__)))
        result = json.loads(out.stdout)
        native.append(result["steps_per_s"])
        loop.append(result["loop_steps_per_s"])
    rust_median, native_median = statistics.median(rust), statistics.median(native)
    return {"task": task, "composuite_bench_steps_per_s": rust_median,
            "native_steps_per_s": native_median, "native_loop_steps_per_s": statistics.median(loop),
            "native_over_rust": native_median / rust_median, "rounds": args.rounds}


def vector_worker(tasks: list[str], threads: int, steps: int) -> float:
    from composuite_ros import CompoSuiteNativeVectorEnv
    envs = CompoSuiteNativeVectorEnv(tasks, threads=threads)
    actions = np.random.default_rng(0).uniform(-1, 1, size=(steps, len(tasks), 8))
    envs.reset(seed=0)
    for action in actions[:50]:
        envs.step(action)
    start = time.perf_counter()
    for action in actions:
        envs.step(action)
    return steps * len(tasks) / (time.perf_counter() - start)


def measure_vector(args, num_envs: int) -> dict:
    tasks = [REFERENCE_TASKS[i % 4] for i in range(num_envs)]
    steps = max(50, args.steps // num_envs)
    rates: dict[int, list[float]] = {1: [], 2: []}
    for _ in range(args.rounds):
        for threads in (1, 2):
            code = (f"import bench_python; print(bench_python.vector_worker({tasks!r}, {threads}, {steps}))")
            out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True,
                                 cwd=os.path.dirname(os.path.abspath(__file__)))
            rates[threads].append(float(out.stdout))
    one, two = statistics.median(rates[1]), statistics.median(rates[2])
    return {"num_envs": num_envs, "steps_per_s_1_thread": one, "steps_per_s_2_threads": two,
            "speedup": two / one, "rounds": args.rounds}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--composuite", required=True, help="the release `composuite` binary")
    parser.add_argument("--tasks", nargs="+", default=REFERENCE_TASKS, metavar="TASK")
    parser.add_argument("--steps", type=int, default=2000, help="steps timed per round (default 2000)")
    parser.add_argument("--rounds", type=int, default=5, help="alternating rounds, median (default 5)")
    parser.add_argument("--envs", type=int, nargs="+", default=[2, 4, 8], help="vector env sizes")
    parser.add_argument("--core", type=int, default=0, help="core the single-env runs are pinned to")
    parser.add_argument("--json", action="store_true", help="print JSON instead of tables")
    args = parser.parse_args()
    if args.steps < 1 or args.rounds < 1:
        parser.error("--steps and --rounds must be at least 1")
    single = []
    for task in args.tasks:
        single.append(measure_single(args, task))
        if not args.json:
            r = single[-1]
            print(f"{task:40s} composuite bench {r['composuite_bench_steps_per_s']:7.0f}  native env "
                  f"{r['native_steps_per_s']:7.0f} ({100 * r['native_over_rust']:.1f} %), loop with resets "
                  f"{r['native_loop_steps_per_s']:7.0f} steps/s", flush=True)
    vector = []
    for n in args.envs:
        vector.append(measure_vector(args, n))
        if not args.json:
            r = vector[-1]
            print(f"vector env, {n} envs: 1 thread {r['steps_per_s_1_thread']:7.0f}  2 threads "
                  f"{r['steps_per_s_2_threads']:7.0f} steps/s  ({r['speedup']:.2f}x)", flush=True)
    if args.json:
        print(json.dumps({"single": single, "vector": vector}, indent=1))


if __name__ == "__main__":
    main()
