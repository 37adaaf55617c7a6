"""Speed of the in-process Python environments (composuite_ros.native), printed, asserted nowhere.

    python bench_python.py --composuite PATH [--tasks T ...] [--steps N] [--rounds R] [--json]
                           [--reference-python PATH --composuite-src DIR]

1. One `CompoSuiteNativeEnv`, uniform random reference actions (drawn beforehand), a reset every
   500 steps (or when an episode ends), pinned to one core — beside `composuite bench` on the same
   task and core, alternating, median of the rounds. Steps/s counts the time inside `step()`
   only, as `composuite bench` does; "loop" is the whole loop, resets included.
   With --reference-python (the reference venv's interpreter, scripts/reference-venv) and
   --composuite-src (an extracted CompoSuite 1fa36f6 checkout), every round also times the
   ORIGINAL CompoSuite on the same task, core and number of steps in a new process
   (tests/reference/bench_reference.py: the protocol of docs/src/reference-speed.md), and the
   output adds its median steps/s and the ratio native env / reference per core.
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


HERE = os.path.dirname(os.path.abspath(__file__))
BENCH_REFERENCE = os.path.join(HERE, os.pardir, "reference", "bench_reference.py")


def reference_run(args, task: str) -> dict:
    """One run of the original CompoSuite in its own venv, pinned to the same core."""
    cmd = [args.reference_python, BENCH_REFERENCE, "--task", task, "--steps", str(args.steps),
           "--composuite-src", args.composuite_src]
    out = subprocess.run(pinned(cmd, args.core), capture_output=True, text=True)
    if out.returncode != 0:
        sys.exit(f"bench_python: the reference run failed ({' '.join(cmd)}):\n{out.stderr[-3000:]}")
    return json.loads(out.stdout.strip().splitlines()[-1])


def measure_single(args, task: str) -> dict:
    rust, native, loop = [], [], []
    reference: dict[str, list[float]] = {key: [] for key in ("steps_per_s", "loop_steps_per_s", "reset_s",
                                                              "build_s")}
    for _ in range(args.rounds):
        out = subprocess.run(pinned([args.composuite, "bench", "--tasks", task, "--steps", str(args.steps),
                                     "--json"], args.core), capture_output=True, text=True, check=True)
        rust.append(json.loads(out.stdout)[0]["steps_per_s"])
        code = (f"import json, bench_python; print(json.dumps(bench_python.single_env_worker("
                f"{task!r}, {args.steps})))")
        out = subprocess.run(pinned([sys.executable, "-c", code], args.core), capture_output=True,
                             text=True, check=True, cwd=HERE)
        result = json.loads(out.stdout)
        native.append(result["steps_per_s"])
        loop.append(result["loop_steps_per_s"])
        if args.reference_python:
            result = reference_run(args, task)
            for key, values in reference.items():
                values.append(result[key])
    rust_median, native_median = statistics.median(rust), statistics.median(native)
    loop_median = statistics.median(loop)
    row = {"task": task, "composuite_bench_steps_per_s": rust_median,
           "native_steps_per_s": native_median, "native_loop_steps_per_s": loop_median,
           "native_over_rust": native_median / rust_median, "rounds": args.rounds}
    if args.reference_python:
        ref = {key: statistics.median(values) for key, values in reference.items()}
        row.update({"reference_steps_per_s": ref["steps_per_s"],
                    "reference_loop_steps_per_s": ref["loop_steps_per_s"],
                    "reference_reset_s": ref["reset_s"], "reference_build_s": ref["build_s"],
                    "native_over_reference": native_median / ref["steps_per_s"],
                    "native_loop_over_reference_loop": loop_median / ref["loop_steps_per_s"]})
    return row


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
                                 cwd=HERE)
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
    parser.add_argument("--envs", type=int, nargs="*", default=[2, 4, 8],
                        help="vector env sizes (default 2 4 8; none: skip the vector env part)")
    parser.add_argument("--core", type=int, default=0, help="core the single-env runs are pinned to")
    parser.add_argument("--json", action="store_true", help="print JSON instead of tables")
    parser.add_argument("--reference-python", metavar="PATH",
                        help="also time the original CompoSuite with this interpreter (the reference venv's)")
    parser.add_argument("--composuite-src", metavar="DIR",
                        help="extracted CompoSuite 1fa36f6 checkout (with --reference-python)")
    args = parser.parse_args()
    if args.steps < 1 or args.rounds < 1:
        parser.error("--steps and --rounds must be at least 1")
    if bool(args.reference_python) != bool(args.composuite_src):
        parser.error("--reference-python and --composuite-src go together")
    if args.composuite_src:
        args.composuite_src = os.path.abspath(args.composuite_src)
        if not os.path.isfile(os.path.join(args.composuite_src, "composuite", "__init__.py")):
            parser.error(f"--composuite-src {args.composuite_src}: no composuite/__init__.py in it")
    single = []
    for task in args.tasks:
        single.append(measure_single(args, task))
        if not args.json:
            r = single[-1]
            print(f"{task:40s} composuite bench {r['composuite_bench_steps_per_s']:7.0f}  native env "
                  f"{r['native_steps_per_s']:7.0f} ({100 * r['native_over_rust']:.1f} %), loop with resets "
                  f"{r['native_loop_steps_per_s']:7.0f} steps/s"
                  + (f"  reference {r['reference_steps_per_s']:5.1f}, loop "
                     f"{r['reference_loop_steps_per_s']:5.1f} steps/s  native/reference "
                     f"{r['native_over_reference']:5.1f}x (loops {r['native_loop_over_reference_loop']:5.1f}x)"
                     if args.reference_python else ""),
                  flush=True)
    if args.reference_python and not args.json:
        ratio = statistics.median(r["native_over_reference"] for r in single)
        print(f"native env vs reference, median over {len(single)} tasks: {ratio:.1f}x steps/s per core "
              f"(goal: at least 10x)", flush=True)
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
