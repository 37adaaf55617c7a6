"""What recording costs: the same lockstep session (`composuite session`, one environment, a
built-in policy over ROS 2) run without the recorder (`--no-record`) and with it, alternately;
prints lockstep steps/s of each and the ratio, each process's CPU per env step with and
without recording (agent, sim, reward, task_manager, recorder), the bag's bytes per env step,
and the recorder's CPU and RSS sampled once a second over the recorded runs (RSS after warm-up,
at the end, and its growth).

Run inside the loopback-only namespace; `scripts/bench-recording` does that and builds the
release binary first. Figures only — nothing is asserted.

    python tests/py/bench_recording.py --composuite target/release/composuite --steps 20000
"""

from __future__ import annotations

import argparse
import json
import re
import statistics
import subprocess
import sys
import tempfile
import threading
import time
from pathlib import Path

from node_suite import cpu_seconds, node_processes, rss_bytes

HORIZON = 500
# For the soak's progress lines only: bag bytes per env step measured on the default session.
BYTES_PER_STEP_GUESS = 558


def sample(pid: int) -> tuple[float, int] | None:
    """(CPU seconds, RSS bytes) of `pid`, or None once it is gone."""
    try:
        cpu = cpu_seconds(pid)
        rss = rss_bytes(pid)
        return cpu, rss
    except (OSError, IndexError, ValueError):
        return None


class RecorderWatch(threading.Thread):
    """Samples the session's recorder once a second until it exits; with `report_every` > 0 also
    prints the recorder's and the sim's RSS and the bag's size that often (a soak)."""

    def __init__(self, session: subprocess.Popen, bag: Path, report_every: float = 0.0):
        super().__init__(daemon=True)
        self.session = session
        self.bag = bag
        self.report_every = report_every
        self.samples: list[tuple[float, float, int]] = []  # (wall, cpu s, rss bytes)

    def report(self, started: float, rss: int) -> None:
        sim = next(iter(node_processes("", "sim")), None)
        sim_rss = sample(sim) if sim else None
        bag = sum(f.stat().st_size for f in self.bag.iterdir()) if self.bag.is_dir() else 0
        print(f"rss: {time.monotonic() - started:7.0f} s  recorder {rss / 1e6:.1f} MB  "
              f"sim {sim_rss[1] / 1e6 if sim_rss else float('nan'):.1f} MB  bag {bag / 1e6:.0f} MB "
              f"(~{bag / BYTES_PER_STEP_GUESS / 1e3:.0f} k steps)", file=sys.stderr, flush=True)

    def run(self) -> None:
        pid = None
        while self.session.poll() is None and pid is None:
            # The recorder node writing this session's bag (`... -p output:=BAG`).
            pid = next(iter(node_processes(f"output:={self.bag}", "recorder")), None)
            time.sleep(0.05)
        started = last_report = time.monotonic()
        while pid is not None and self.session.poll() is None:
            got = sample(pid)
            if got is None:
                break
            self.samples.append((time.monotonic(), *got))
            if self.report_every > 0 and time.monotonic() - last_report >= self.report_every:
                last_report = time.monotonic()
                self.report(started, got[1])
            time.sleep(1.0)


class CpuWatch(threading.Thread):
    """CPU seconds of each process of a session — its agent (the session process itself), sim,
    reward, task_manager and recorder — sampled once a second until the session ends: where a
    step's CPU goes with and without the recorder."""

    def __init__(self, session: subprocess.Popen, bag: Path | None):
        super().__init__(daemon=True)
        self.session = session
        self.bag = bag
        # kind -> [(wall, cpu s) first sample, last sample]
        self.spans: dict[str, list[tuple[float, float]]] = {}

    def run(self) -> None:
        pids: dict[str, int] = {}
        while self.session.poll() is None:
            if len(pids) < 4:  # the agent and the environment's three nodes
                pids["agent"] = self.session.pid
                for kind in ("sim", "reward", "task_manager"):
                    found = node_processes(f"__ns:=/session_{self.session.pid} ", kind)
                    if found:
                        pids[kind] = found[0]
            if self.bag and "recorder" not in pids:
                found = node_processes(f"output:={self.bag}", "recorder")
                if found:
                    pids["recorder"] = found[0]
            now = time.monotonic()
            for kind, pid in pids.items():
                got = sample(pid)
                if got is not None:
                    span = self.spans.setdefault(kind, [(now, got[0])])
                    span[1:] = [(now, got[0])]
            time.sleep(1.0)

    def ms_per_step(self, steps_per_s: float) -> dict[str, float]:
        """Each process's CPU per env step (ms) over the sampled window."""
        out = {}
        for kind, span in self.spans.items():
            (t0, c0), (t1, c1) = span[0], span[-1]
            if t1 > t0:
                out[kind] = 1e3 * (c1 - c0) / (t1 - t0) / steps_per_s
        return out


def run_session(composuite: str, task: str, policy: str, episodes: int, record: bool,
                out: Path, report_every: float = 0.0, max_bag_size: int = 0) -> dict:
    args = [composuite, "session", "--tasks", task, "--episodes", str(episodes), "--policy", policy,
            "--horizon", str(HORIZON), "--seed", "0", "--out", str(out)]
    if not record:
        args.append("--no-record")
    elif max_bag_size:
        args += ["--max-bag-size", str(max_bag_size)]
    start = time.monotonic()
    session = subprocess.Popen(args, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    watch = RecorderWatch(session, out / "bag", report_every) if record else None
    cpu = CpuWatch(session, out / "bag" if record else None)
    cpu.start()
    if watch:
        watch.start()
    stdout, stderr = session.communicate()
    wall = time.monotonic() - start
    cpu.join()
    if watch:
        watch.join()
    if session.returncode != 0:
        sys.exit(f"session failed ({session.returncode}):\n{stderr[-3000:]}")
    rates = re.findall(r"([\d.]+) steps/s", stderr)
    result = {"record": record, "steps_per_s": float(rates[-1]), "wall_s": wall}
    result["cpu_ms_per_step"] = cpu.ms_per_step(result["steps_per_s"])
    if record:
        steps = episodes * HORIZON
        bag_bytes = sum(f.stat().st_size for f in (out / "bag").iterdir())
        result["bag_bytes_per_step"] = bag_bytes / steps
        samples = watch.samples
        if len(samples) >= 3:
            warm = samples[max(1, len(samples) // 10)]
            last = samples[-1]
            result["recorder_cpu_percent"] = 100 * (last[1] - samples[0][1]) / max(last[0] - samples[0][0], 1e-9)
            result["recorder_rss_mb_after_warmup"] = warm[2] / 1e6
            result["recorder_rss_mb_end"] = last[2] / 1e6
            result["recorder_rss_mb_max"] = max(s[2] for s in samples) / 1e6
            result["recorder_rss_growth_mb"] = (last[2] - warm[2]) / 1e6
    return result


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--composuite", required=True, help="the composuite binary (release build)")
    parser.add_argument("--steps", type=int, default=20_000, help="env steps per run (multiple of 500)")
    parser.add_argument("--rounds", type=int, default=2, help="runs of each kind, alternating")
    parser.add_argument("--task", default="IIWA/box/no_obstacle/pick_place")
    parser.add_argument("--policy", default="zero", help="expert, planned, random or zero (the cheapest agent)")
    parser.add_argument("--record-only", action="store_true",
                        help="only the recorded runs (for the recorder's RSS over a long session)")
    parser.add_argument("--rss-every", type=float, default=0.0, metavar="SECONDS",
                        help="also print the recorder's and the sim's RSS and the bag's size this often")
    parser.add_argument("--max-bag-size", type=int, default=0, metavar="BYTES",
                        help="split the recorded bags into files of this size (session --max-bag-size)")
    parser.add_argument("--json", action="store_true")
    args = parser.parse_args()
    episodes = max(1, args.steps // HORIZON)
    results = []
    with tempfile.TemporaryDirectory() as tmp:
        for round_ in range(args.rounds):
            for record in (True,) if args.record_only else (False, True):
                out = Path(tmp) / f"{round_}_{int(record)}"
                result = run_session(args.composuite, args.task, args.policy, episodes, record, out,
                                     args.rss_every, args.max_bag_size)
                results.append(result)
                print(f"round {round_ + 1}, {'recording' if record else 'not recording'}: "
                      f"{result['steps_per_s']:.0f} steps/s", file=sys.stderr, flush=True)
                # Bags are large: keep only the figures.
                subprocess.run(["rm", "-rf", str(out)], check=False)
    recorded = [r for r in results if r["record"]]
    with_bag = statistics.median(r["steps_per_s"] for r in recorded)
    plain = statistics.median([r["steps_per_s"] for r in results if not r["record"]] or [float("nan")])
    summary = {
        "task": args.task, "policy": args.policy, "steps_per_run": episodes * HORIZON, "rounds": args.rounds,
        "steps_per_s_without_recording": plain, "steps_per_s_recording": with_bag,
        "recording_cost_percent": 100 * (1 - with_bag / plain),
        "bag_bytes_per_step": statistics.median(r["bag_bytes_per_step"] for r in recorded),
    }
    kinds = ("agent", "sim", "reward", "task_manager", "recorder")
    for label, runs in (("without_recording", [r for r in results if not r["record"]]),
                        ("recording", recorded)):
        if runs:
            summary[f"cpu_ms_per_step_{label}"] = {
                k: statistics.median(r["cpu_ms_per_step"][k] for r in runs if k in r["cpu_ms_per_step"])
                for k in kinds if any(k in r["cpu_ms_per_step"] for r in runs)}
    last = recorded[-1]
    for key in ("recorder_cpu_percent", "recorder_rss_mb_after_warmup", "recorder_rss_mb_end",
                "recorder_rss_mb_max", "recorder_rss_growth_mb"):
        if key in last:
            summary[key] = last[key]
    if args.json:
        print(json.dumps(summary, indent=2))
        return
    print(f"{args.task}, policy {args.policy}, {episodes * HORIZON} steps per run, median of {args.rounds}:")
    if args.record_only:
        print(f"  lockstep steps/s recording {with_bag:.0f}")
    else:
        print(f"  lockstep steps/s without recording {plain:.0f}, recording {with_bag:.0f} "
              f"(recording costs {summary['recording_cost_percent']:.1f} %)")
    for label in ("without_recording", "recording"):
        per = summary.get(f"cpu_ms_per_step_{label}")
        if per:
            print(f"  CPU ms per env step, {label.replace('_', ' ')}: "
                  + ", ".join(f"{k} {v:.2f}" for k, v in per.items())
                  + f" (sum {sum(per.values()):.2f})")
    print(f"  bag: {summary['bag_bytes_per_step']:.0f} bytes per env step (zstd-compressed MCAP)")
    if "recorder_cpu_percent" in summary:
        print(f"  recorder (last run): CPU {summary['recorder_cpu_percent']:.0f} % of a core, RSS "
              f"{summary['recorder_rss_mb_after_warmup']:.1f} MB after warm-up, "
              f"{summary['recorder_rss_mb_end']:.1f} MB at the end (max {summary['recorder_rss_mb_max']:.1f}, "
              f"growth {summary['recorder_rss_growth_mb']:+.2f} MB)")


if __name__ == "__main__":
    main()
