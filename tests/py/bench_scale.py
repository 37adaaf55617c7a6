"""What N environments on one host cost: `composuite launch --envs N` composed (one process,
one DDS participant: the default) or `--isolate` (a process per node). Figures only, nothing is
asserted. Run through `scripts/bench-scale`, which builds the release binaries and enters the
loopback-only namespace.

    python tests/py/bench_scale.py --envs 1 8 32 64 [--isolate | --processes K] [--threads N] [--agents K] [--idle 30] [--json]

Per N: processes of the suite, RSS in all and per environment, the suite's idle CPU (% of one
core) over `--idle` seconds once every environment answered, the seconds from launch until
every node said it is up and until every environment answered a reset (an rclpy agent), the
lockstep steps/s of env_00 stepped alone by one `CompoSuiteRosEnv` while the others idle (and
its p99 step), and the aggregate steps/s with every environment stepped together by one
`CompoSuiteRosVectorEnv` (or, with `--agents K`, by K agent processes at once).
"""

from __future__ import annotations

import argparse
import json
import multiprocessing
import os
import signal
import subprocess
import tempfile
import time
from pathlib import Path

import numpy as np

import node_suite
from composuite_ros import CompoSuiteRosEnv
from composuite_ros.vector import CompoSuiteRosVectorEnv

TASK = "IIWA/box/no_obstacle/pick_place"
NAMESPACE = "/scale"


def process_tree(root: int) -> list[int]:
    """`root` and every process below it."""
    children: dict[int, list[int]] = {}
    for entry in Path("/proc").iterdir():
        if not entry.name.isdigit():
            continue
        try:
            stat = (entry / "stat").read_text()
        except OSError:
            continue
        parent = int(stat.rsplit(")", 1)[1].split()[1])
        children.setdefault(parent, []).append(int(entry.name))
    tree, stack = [], [root]
    while stack:
        pid = stack.pop()
        tree.append(pid)
        stack.extend(children.get(pid, []))
    return tree


def rss_mb(pid: int) -> float:
    """Resident MB of `pid`, 0 once it is gone."""
    try:
        return node_suite.rss_bytes(pid) / 2**20
    except (OSError, IndexError, ValueError):
        return 0.0


def tree_cpu_seconds(root: int) -> float:
    return sum(node_suite.cpu_seconds(pid) for pid in process_tree(root))


def thread_cpu_ticks(root: int) -> dict[str, int]:
    """Clock ticks (user + system) of every thread below `root`, summed by thread name (digits
    dropped, so `sim-3` and `sim-41` count together)."""
    ticks: dict[str, int] = {}
    for pid in process_tree(root):
        for task in Path(f"/proc/{pid}/task").glob("*"):
            try:
                stat = (task / "stat").read_text()
            except OSError:
                continue
            name = stat[stat.index("(") + 1:stat.rindex(")")].rstrip("0123456789-_ ")
            fields = stat.rsplit(")", 1)[1].split()
            ticks[name] = ticks.get(name, 0) + int(fields[11]) + int(fields[12])
    return ticks


def timed_steps(namespaces: list[str], steps: int, seed: int, before=lambda: None) -> float:
    """A vector env over `namespaces`, reset; `before()`; then the seconds `steps` steps take."""
    vector = CompoSuiteRosVectorEnv(namespaces, TASK, timeout=60.0)
    vector.reset(seed=0)
    rng = np.random.default_rng(seed)
    before()
    t0 = time.perf_counter()
    for _ in range(steps):
        vector.step(rng.uniform(-1, 1, (len(namespaces), 8)))
    elapsed = time.perf_counter() - t0
    vector.close()
    return elapsed


def agent_process(namespaces: list[str], steps: int, ready, done) -> None:
    """One agent of `step_together`: its steps start once every agent is ready; its elapsed
    seconds go to `done`."""
    done.put(timed_steps(namespaces, steps, len(namespaces), ready.wait))


def step_together(namespaces: list[str], steps: int, agents: int) -> float:
    """Aggregate lockstep steps/s with every environment stepped at once: one vector env over all
    (agents = 1), or `agents` processes each stepping every agents-th environment."""
    agents = min(agents, len(namespaces))
    if agents == 1:
        return steps * len(namespaces) / timed_steps(namespaces, steps, 0)
    context = multiprocessing.get_context("spawn")
    ready, done = context.Barrier(agents + 1), context.Queue()
    workers = [context.Process(target=agent_process,
                               args=(namespaces[k::agents], steps, ready, done))
               for k in range(agents)]
    for w in workers:
        w.start()
    ready.wait(timeout=300)
    elapsed = max(done.get(timeout=600) for _ in workers)
    for w in workers:
        w.join(timeout=60)
    return steps * len(namespaces) / elapsed


def bench(n: int, isolate: bool, processes: int, threads: int | None, agents: int, idle: float,
          steps: int, breakdown: bool) -> dict:
    folder = Path(tempfile.mkdtemp(prefix="bench_scale_"))
    domain = node_suite.random_domain()
    env = {k: v for k, v in os.environ.items() if not k.startswith("ROS_")}
    env["ROS_DOMAIN_ID"] = str(domain)
    os.environ["ROS_DOMAIN_ID"] = str(domain)
    extra = (["--envs", str(n)] if n > 1 else []) + (["--isolate"] if isolate else []) \
        + (["--processes", str(min(processes, n))] if processes > 1 and n > 1 else []) \
        + (["--threads", str(threads)] if threads and n > 1 and not isolate else [])
    log = folder / "launch.stderr"
    started = time.monotonic()
    with open(log, "wb") as stderr:
        launch = subprocess.Popen(
            [str(node_suite.node_dir() / "composuite"), "launch", "--task", TASK, "--namespace",
             NAMESPACE, "--service-mapping", "fastdds", "--log-level", "info", *extra],
            env=env, stdin=subprocess.DEVNULL, stdout=stderr, stderr=stderr)
    namespaces = [NAMESPACE] if n == 1 else [f"{NAMESPACE}/env_{i:02}" for i in range(n)]
    try:
        while log.read_text(errors="replace").count(" up") < 3 * n:
            if launch.poll() is not None or time.monotonic() - started > 600:
                raise RuntimeError(f"the suite did not come up:\n{log.read_text()[-3000:]}")
            time.sleep(0.05)
        up_s = time.monotonic() - started
        vector = CompoSuiteRosVectorEnv(namespaces, TASK, timeout=60.0)
        vector.reset(seed=0)
        answered_s = time.monotonic() - started
        vector.close()
        time.sleep(2.0)  # the agent's participant leaves the graph
        tree = process_tree(launch.pid)
        rss = sum(rss_mb(pid) for pid in tree)
        cpu0 = tree_cpu_seconds(launch.pid)
        threads0 = thread_cpu_ticks(launch.pid) if breakdown else {}
        time.sleep(idle)
        idle_cpu = 100 * (tree_cpu_seconds(launch.pid) - cpu0) / idle
        if breakdown:
            threads1 = thread_cpu_ticks(launch.pid)
            tick = os.sysconf("SC_CLK_TCK")
            spent = sorted(((threads1[k] - threads0.get(k, 0), k) for k in threads1), reverse=True)
            print(f"  idle CPU by thread name ({n} envs, % of one core over {idle:.0f} s):")
            for t, name in spent[:12]:
                if t:
                    print(f"    {100 * t / tick / idle:6.2f}%  {name}", flush=True)

        rng = np.random.default_rng(0)
        with CompoSuiteRosEnv(TASK, namespaces[0], timeout=30.0) as single:
            single.reset(seed=0)
            latencies = []
            t0 = time.perf_counter()
            for _ in range(steps):
                t = time.perf_counter()
                _, _, terminated, truncated, _ = single.step(rng.uniform(-1, 1, 8))
                latencies.append(time.perf_counter() - t)
                if terminated or truncated:
                    single.reset()
            alone = steps / (time.perf_counter() - t0)
        together = step_together(namespaces, max(20, steps // n), agents)
    finally:
        launch.send_signal(signal.SIGINT)
        try:
            launch.wait(timeout=60)
        except subprocess.TimeoutExpired:
            launch.kill()
    mode = ("isolate" if isolate or n == 1
            else f"{min(processes, n)} procs" if processes > 1 else "composed")
    return {"envs": n, "mode": mode,
            "processes": len(tree), "rss_mb": rss, "rss_per_env_mb": rss / n,
            "idle_cpu_percent": idle_cpu, "up_s": up_s, "answered_s": answered_s,
            "alone_steps_per_s": alone, "alone_p99_ms": 1e3 * float(np.percentile(latencies, 99)),
            "together_steps_per_s": together}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__,
                                     formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--envs", type=int, nargs="+", default=[1, 8, 32, 64])
    parser.add_argument("--isolate", action="store_true", help="a process per node (the old way)")
    parser.add_argument("--idle", type=float, default=30.0, help="seconds of idle CPU measurement")
    parser.add_argument("--steps", type=int, default=500, help="steps of env_00 stepped alone")
    parser.add_argument("--processes", type=int, default=1,
                        help="composed environments split over this many processes")
    parser.add_argument("--threads", type=int, default=None,
                        help="threads stepping the composed environments' physics (launch --threads; "
                             "default: launch's, one per core)")
    parser.add_argument("--agents", type=int, default=1,
                        help="step all environments with this many agent processes (each a vector "
                             "env over every K-th environment) instead of one")
    parser.add_argument("--json", action="store_true")
    parser.add_argument("--breakdown", action="store_true",
                        help="also print the idle CPU by thread name (where it goes)")
    args = parser.parse_args()
    if any(n < 1 for n in args.envs) or args.idle <= 0 or args.steps < 1 or args.processes < 1 \
            or args.agents < 1 or (args.threads is not None and args.threads < 1):
        parser.error("--envs, --idle, --steps, --processes, --threads and --agents must be positive")
    rows = []
    if not args.json:
        print("envs  mode      procs  RSS MB  per env  idle CPU  up s  answered s  alone steps/s (p99 ms)"
              "  together steps/s", flush=True)
    for n in args.envs:
        r = bench(n, args.isolate, args.processes, args.threads, args.agents, args.idle, args.steps,
                  args.breakdown)
        rows.append(r)
        if not args.json:
            print(f"{r['envs']:4d}  {r['mode']:8s}  {r['processes']:5d}  {r['rss_mb']:6.0f}  "
                  f"{r['rss_per_env_mb']:7.1f}  {r['idle_cpu_percent']:7.1f}%  {r['up_s']:4.1f}  "
                  f"{r['answered_s']:10.1f}  {r['alone_steps_per_s']:7.0f} ({r['alone_p99_ms']:.1f})"
                  f"  {r['together_steps_per_s']:10.0f}", flush=True)
    if args.json:
        print(json.dumps(rows, indent=1))


if __name__ == "__main__":
    main()
