"""What DDS-Security costs a lockstep episode: the suite (three nodes, one environment) driven
by the Fast DDS agent of tests/interop/fastdds_secure_peer, plain and secured (Enforce, every
message signed, every sample encrypted), alternating. Prints env steps/s and the CPU per step of
the suite's processes and of the agent; asserts nothing.

    python tests/py/bench_secure.py --composuite PATH [--steps N] [--rounds R] [--json]

Only run inside scripts/netns-isolate (scripts/bench-ros --secure does both)."""

from __future__ import annotations

import argparse
import json
import os
import signal
import subprocess
import tempfile
import time
from pathlib import Path

import node_suite

TASK = "IIWA/box/no_obstacle/pick_place"
NS = "/bench"
CLOCK_TICKS = os.sysconf("SC_CLK_TCK")


def tree_cpu_seconds(root: int) -> float:
    """User + system CPU seconds of process `root` and every descendant alive now, threads that
    have exited included (/proc/PID/stat; clock ticks, 10 ms: over a 500-step episode a few per
    cent of the agent's figure, under 2 % of the suite's)."""
    stats = {}
    for entry in Path("/proc").iterdir():
        if entry.name.isdigit():
            try:
                fields = (entry / "stat").read_text().rsplit(")", 1)[1].split()
            except OSError:
                continue
            stats[int(entry.name)] = (int(fields[1]), int(fields[11]) + int(fields[12]))
    total, todo = 0, [root]
    while todo:
        pid = todo.pop()
        total += stats.get(pid, (0, 0))[1]
        todo.extend(child for child, (ppid, _) in stats.items() if ppid == pid)
    return total / CLOCK_TICKS


def keystore(composuite: Path, domain: int, where: Path) -> Path:
    ks = where / "keystore"
    for args in (["create-keystore", str(ks)], ["create-enclave", str(ks), "/"],
                 ["create-enclave", str(ks), "/agent"]):
        subprocess.run([str(composuite), "security", *args, "--domain-id", str(domain)],
                       check=True, capture_output=True)
    return ks


def episode(composuite: Path, peer: Path, domain: int, steps: int, ks: Path | None,
            log: Path) -> dict:
    """One launch of the suite and one agent episode of `steps` steps; the figures between the
    agent's first and last step (discovery, key exchange and warm-up left out)."""
    env = {k: v for k, v in os.environ.items() if not k.startswith("ROS_")}
    env["ROS_DOMAIN_ID"] = str(domain)
    if ks is not None:
        env.update(ROS_SECURITY_ENABLE="true", ROS_SECURITY_STRATEGY="Enforce",
                   ROS_SECURITY_KEYSTORE=str(ks))
    with open(log, "wb") as out:
        suite = subprocess.Popen(
            [str(composuite), "launch", "--task", TASK, "--namespace", NS,
             "--service-mapping", "fastdds"], env=env, stdout=out, stderr=out)
    try:
        deadline = time.monotonic() + 30
        while not all(f"{NS}/{node} up" in log.read_text(errors="replace")
                      for node in ("task_manager", "sim", "reward")):
            if suite.poll() is not None or time.monotonic() > deadline:
                raise RuntimeError(f"the suite did not come up:\n{log.read_text()[-3000:]}")
            time.sleep(0.05)
        args = [str(peer), "--domain", str(domain), "--namespace", NS, "--seed", "1",
                "--steps", str(steps)]
        if ks is not None:
            args += ["--enclave", str(ks / "enclaves" / "agent")]
        agent = subprocess.Popen(args, env={k: v for k, v in env.items()
                                            if not k.startswith("ROS_")},
                                 stdout=subprocess.PIPE, stderr=subprocess.DEVNULL, text=True)
        marks = {}
        for line in agent.stdout:
            step = json.loads(line).get("step")
            if step in (1, steps):
                marks[step] = (time.monotonic(), tree_cpu_seconds(suite.pid),
                               tree_cpu_seconds(agent.pid))
        if agent.wait(timeout=60) != 0 or len(marks) != 2:
            raise RuntimeError(f"the agent failed (exit {agent.returncode})")
    finally:
        suite.send_signal(signal.SIGINT)
        try:
            suite.wait(timeout=20)
        except subprocess.TimeoutExpired:
            suite.kill()
    (t0, s0, a0), (t1, s1, a1) = marks[1], marks[steps]
    n = steps - 1
    return {"steps_per_s": n / (t1 - t0), "suite_cpu_us_per_step": 1e6 * (s1 - s0) / n,
            "agent_cpu_us_per_step": 1e6 * (a1 - a0) / n}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--composuite", type=Path, required=True, help="the composuite binary")
    parser.add_argument("--steps", type=int, default=400, help="steps per episode (2-500)")
    parser.add_argument("--rounds", type=int, default=2, help="plain/secured pairs to run")
    parser.add_argument("--json", action="store_true", help="one JSON line per episode too")
    args = parser.parse_args()
    if not 2 <= args.steps <= 500:
        parser.error(f"--steps {args.steps}: between 2 and 500 (an episode's horizon)")
    peer = node_suite.fastdds_peer()
    domain = 1 + os.getpid() % node_suite.MAX_TEST_DOMAIN
    results: dict[str, list[dict]] = {"plain": [], "secured": []}
    with tempfile.TemporaryDirectory(prefix="bench-secure-") as scratch:
        ks = keystore(args.composuite, domain, Path(scratch))
        for round_ in range(args.rounds):
            for mode in ("plain", "secured"):
                figures = episode(args.composuite, peer, domain, args.steps,
                                  ks if mode == "secured" else None,
                                  Path(scratch) / f"{mode}-{round_}.log")
                results[mode].append(figures)
                if args.json:
                    print(json.dumps({"mode": mode, "round": round_, **figures}))
    print(f"lockstep with the Fast DDS agent, {TASK}, {args.steps} steps, {args.rounds} rounds")
    print(f"{'':8} {'steps/s':>16} {'suite CPU us/step':>20} {'agent CPU us/step':>20}")
    for mode, runs in results.items():
        span = lambda key, f="{:.0f}": "–".join(
            f.format(x) for x in sorted({min(r[key] for r in runs), max(r[key] for r in runs)}))
        print(f"{mode:8} {span('steps_per_s'):>16} {span('suite_cpu_us_per_step'):>20} "
              f"{span('agent_cpu_us_per_step'):>20}")
    ratio = (sum(r["steps_per_s"] for r in results["secured"])
             / sum(r["steps_per_s"] for r in results["plain"]))
    print(f"secured / plain steps/s: {ratio:.2f}")


if __name__ == "__main__":
    main()
