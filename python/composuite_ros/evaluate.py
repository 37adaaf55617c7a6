"""The CompoSuite paper's evaluation protocol, in-process or over running environments of the suite.

    composuite-eval --experiment smallscale --element IIWA --num-train 16 --episodes 5 \\
        --agent random --out runs/eval_iiwa                       # in-process (--backend native)

    composuite launch --envs 2 &
    composuite-eval --experiment smallscale --element IIWA --num-train 16 --episodes 5 \\
        --agent random --namespaces /env_00,/env_01 --out runs/eval_iiwa    # over ROS 2

1. The train/test split is drawn exactly as the reference's `composuite.sample_tasks` (same
   experiment, num_train, element and shuffling seed → the same lists as the paper's
   experiments): in-process by the simulation core, over ROS by the suite's `sample_tasks`
   service, which runs the same code.
2. Every chosen task runs `--episodes` episodes (episode j of every task has seed `--seed` + j),
   spread over the environments, which step concurrently: `--envs` in-process environments on
   the cores (`--backend native`, the default when no `--namespaces` are given), or the suite's
   environments in `--namespaces` (`--backend ros`). For the same agent, split and seeds both
   give the same episodes, bit for bit (only where each ran, `namespace` and `episode`, differ).
3. The paper's metrics: per task the mean return R̄ (sum of the step rewards of an episode,
   averaged over its episodes) and the success rate S̄ (an episode succeeds if any step has
   reward 1); then averaged over the train and over the test tasks, and per axis element.

Agents: `random` (uniform in [-1, 1], seeded per episode), `zero`, or `module:Class` — a class
built with no arguments, once per environment, with `act(observation) -> action` (the 93-value
observation, the reference's 8 actions) and optionally `reset(task, seed)` called at each
episode's start.

Writes into `--out`: episodes.csv (one row per episode), summary.csv and summary.json (the
metrics), and eval.png (with matplotlib installed: `pip install composuite_ros[plots]`).
"""

from __future__ import annotations

import argparse
import csv
import importlib
import json
import sys
import time
from collections.abc import Sequence
from dataclasses import asdict, dataclass
from pathlib import Path

import numpy as np

from . import episode as _episode
from .errors import SuiteNotRunningError
from .tasks import AXES, Task

# The ROS side (rclpy, composuite_msgs) is imported by the ROS backend only, so the in-process
# evaluation runs where no ROS is installed.

BACKENDS = ("native", "ros")

EXPERIMENTS = ("default", "smallscale", "holdout")


# ---- agents -------------------------------------------------------------------------------------

class RandomAgent:
    """Uniform actions in [-1, 1], drawn from a generator seeded by the episode's seed (so the
    run does not depend on which environment an episode lands on)."""

    def __init__(self):
        self.rng = np.random.default_rng(0)

    def reset(self, task: str, seed: int) -> None:
        self.rng = np.random.default_rng(seed)

    def act(self, observation):
        return self.rng.uniform(-1.0, 1.0, size=8)


class ZeroAgent:
    """All-zero actions: the arm holds still, the gripper stays where it drifts."""

    def act(self, observation):
        return np.zeros(8)


def agent_factory(spec: str):
    """`random`, `zero` or `module:Class` → a callable making one agent."""
    if spec == "random":
        return RandomAgent
    if spec == "zero":
        return ZeroAgent
    module_name, _, class_name = spec.partition(":")
    if not module_name or not class_name:
        raise ValueError(f"agent {spec!r} is not random, zero or module:Class")
    try:
        module = importlib.import_module(module_name)
    except ImportError as err:
        raise ValueError(f"agent {spec!r}: cannot import {module_name} ({err}); is it on PYTHONPATH?") from err
    cls = getattr(module, class_name, None)
    if cls is None or not callable(getattr(cls, "act", None)):
        raise ValueError(f"agent {spec!r}: {module_name} has no class {class_name} with an act(observation) method")
    return cls


# ---- results ------------------------------------------------------------------------------------

@dataclass
class EpisodeResult:
    split: str
    task: str
    seed: int
    namespace: str
    episode: int
    length: int
    episode_return: float
    success: bool
    furthest_stage: str


@dataclass
class Metric:
    split: str
    axis: str  # "all" for the split's mean, else the axis of `element`
    element: str
    tasks: int
    episodes: int
    mean_return: float
    success_rate: float


def metrics(results: Sequence[EpisodeResult]) -> list[Metric]:
    """R̄ and S̄ per split (mean over its tasks of each task's mean over episodes) and per axis
    element (over the split's tasks containing it)."""
    per_task: dict[tuple[str, str], list[EpisodeResult]] = {}
    for r in results:
        per_task.setdefault((r.split, r.task), []).append(r)
    task_means = {key: (float(np.mean([e.episode_return for e in eps])),
                        float(np.mean([e.success for e in eps])), len(eps))
                  for key, eps in per_task.items()}
    rows = []
    for split in dict.fromkeys(r.split for r in results):
        groups: dict[tuple[str, str], list[tuple[str, str]]] = {("all", ""): []}
        for (s, task) in task_means:
            if s != split:
                continue
            groups[("all", "")].append((s, task))
            for axis, element in Task.parse(task).elements().items():
                groups.setdefault((axis, element), []).append((s, task))
        order = [("all", "")] + [(axis, e) for axis, elements in AXES.items() for e in elements
                                 if (axis, e) in groups]
        for axis, element in order:
            keys = groups[(axis, element)]
            rows.append(Metric(split, axis, element, len(keys), sum(task_means[k][2] for k in keys),
                               float(np.mean([task_means[k][0] for k in keys])),
                               float(np.mean([task_means[k][1] for k in keys]))))
    return rows


# ---- running ------------------------------------------------------------------------------------

class Progress:
    """One status line on stderr: rewritten in place on a terminal, every 10 % otherwise."""

    def __init__(self, total: int, enabled: bool = True):
        self.total, self.enabled = total, enabled
        self.tty = sys.stderr.isatty()
        self.started = time.monotonic()
        self.last_tenth = -1

    def update(self, done: int, steps: int, successes: int) -> None:
        if not self.enabled:
            return
        elapsed = max(time.monotonic() - self.started, 1e-9)
        line = (f"episodes {done}/{self.total}  {steps / elapsed:,.0f} steps/s  "
                f"success {successes}/{done}" if done else f"episodes 0/{self.total}")
        tenth = done * 10 // max(self.total, 1)
        if self.tty:
            print(f"\r{line}   ", end="" if done < self.total else "\n", file=sys.stderr, flush=True)
        elif tenth != self.last_tenth:
            self.last_tenth = tenth
            print(line, file=sys.stderr, flush=True)


@dataclass
class _Job:
    split: str
    task: str
    seed: int


class _Worker:
    """One environment of the suite running jobs one episode at a time."""

    def __init__(self, channel, agent, use_task_id_obs: bool):
        self.channel, self.agent, self.use_task_id_obs = channel, agent, use_task_id_obs
        self.task: str | None = None
        self.job: _Job | None = None
        self.tracker = None
        self.length = 0

    def start(self, job: _Job) -> None:
        from .env import EpisodeTracker, stamp_ns

        if job.task != self.task:
            self.task = str(self.channel.set_task(Task.parse(job.task)))
        reply = self.channel.reset(job.seed)
        self.job, self.length = job, 0
        self.tracker = EpisodeTracker(stamp_ns(reply.observation))
        if callable(getattr(self.agent, "reset", None)):
            self.agent.reset(job.task, job.seed)
        self._act(reply.observation)

    def _act(self, observation) -> None:
        from .env import flat_observation
        self.channel.send_reference_action(
            agent_action(self.agent, flat_observation(observation, self.use_task_id_obs)))

    def advance(self) -> EpisodeResult | None:
        """Take the arrived step; the finished episode's result, or None (next action sent)."""
        messages = self.channel.take_step()
        self.length += 1
        info = self.tracker.step_info(messages)
        if not self.tracker.done:
            self._act(messages.observation)
            return None
        job, self.job = self.job, None
        return EpisodeResult(job.split, job.task, job.seed, self.channel.namespace, self.channel.episode,
                             self.length, self.tracker.episode_return, self.tracker.success,
                             info["furthest_stage"])


def agent_action(agent, observation: np.ndarray) -> np.ndarray:
    """The agent's action for `observation`, checked: 8 finite values."""
    action = np.asarray(agent.act(observation), dtype=np.float64).reshape(-1)
    if action.shape != (8,) or not np.all(np.isfinite(action)):
        raise ValueError(f"the agent returned {action.tolist()}; it must give 8 finite values")
    return action


def in_job_order(jobs: Sequence[_Job], results: list[EpisodeResult]) -> list[EpisodeResult]:
    order = {(j.split, j.task, j.seed): i for i, j in enumerate(jobs)}
    return sorted(results, key=lambda r: order[(r.split, r.task, r.seed)])


def run_episodes_native(jobs: Sequence[_Job], envs: int | None = None, agent_spec: str = "random", *,
                        use_task_id_obs: bool = True, horizon: int = 500, threads: int | None = None,
                        progress: bool = True) -> list[EpisodeResult]:
    """Run every job (task, seed) as one episode on `envs` in-process environments (default:
    one per core) stepped together; results in job order. An environment's `namespace` is
    `native/<index>`."""
    from . import _native
    from .native import default_threads, record_row
    make_agent = agent_factory(agent_spec)
    n = max(1, min(envs or default_threads(len(jobs)), len(jobs)))
    batch = _native.Batch([jobs[i].task for i in range(n)], threads=threads or default_threads(n),
                          horizon=horizon, use_task_id_obs=use_task_id_obs)
    period_ns = batch.control_period_ns
    end_reasons = _native.end_reasons(horizon)
    agents = [make_agent() for _ in range(n)]
    tasks = batch.tasks()
    stage_names = [list(batch.stage_names(i)) for i in range(n)]
    running: list[_Job | None] = [None] * n
    trackers: list[_episode.EpisodeTracker | None] = [None] * n
    modes, seeds, actions, observations = batch.modes, batch.seeds, batch.actions, batch.observations
    queue = list(jobs)
    queue.reverse()
    results: list[EpisodeResult] = []
    bar = Progress(len(jobs), progress)
    steps = successes = 0
    bar.update(0, 0, 0)
    while queue or any(running):
        modes[:] = _native.MODE_IDLE
        starting = []
        for i in range(n):
            if running[i] is not None or not queue:
                continue
            starting.append(i)
            job = running[i] = queue.pop()
            if job.task != tasks[i]:
                tasks[i] = batch.set_task(i, job.task)
                stage_names[i] = list(batch.stage_names(i))
            modes[i], seeds[i] = _native.MODE_RESET, job.seed
            trackers[i] = _episode.EpisodeTracker()
        if starting:
            batch.run()
            for i in starting:
                if callable(getattr(agents[i], "reset", None)):
                    agents[i].reset(running[i].task, running[i].seed)
        active = [i for i in range(n) if running[i] is not None]
        for i in active:
            actions[i] = agent_action(agents[i], observations[i].copy())
            modes[i] = _native.MODE_STEP
        batch.run()
        for i in active:
            _, _, _, info = record_row(trackers[i], batch, i, stage_names[i], end_reasons, period_ns)
            steps += 1
            if trackers[i].done:
                job, running[i] = running[i], None
                results.append(EpisodeResult(job.split, job.task, job.seed, f"native/{i}", batch.episode(i),
                                             info["step"], trackers[i].episode_return, trackers[i].success,
                                             info["furthest_stage"]))
                successes += results[-1].success
                bar.update(len(results), steps, successes)
    return in_job_order(jobs, results)


def run_episodes(jobs: Sequence[_Job], namespaces: Sequence[str], agent_spec: str = "random", *,
                 use_task_id_obs: bool = True, domain_id: int | None = None, timeout: float = 10.0,
                 progress: bool = True) -> list[EpisodeResult]:
    """Run every job (task, seed) as one episode over the suite's environments in `namespaces`;
    results in job order."""
    from ._link import Channel, Participant
    make_agent = agent_factory(agent_spec)
    participant = Participant("composuite_eval", domain_id)
    results: list[EpisodeResult] = []
    try:
        workers = [_Worker(Channel(participant, ns, timeout), make_agent(), use_task_id_obs)
                   for ns in namespaces]
        seconds = workers[0].channel.discovery_timeout
        if not participant.spin_for(lambda: not any(w.channel.missing() for w in workers), seconds):
            raise next(w.channel for w in workers if w.channel.missing()).not_running_error(
                "waiting for the suite's topics and services", seconds)
        queue = list(jobs)
        queue.reverse()
        bar = Progress(len(jobs), progress)
        steps = successes = 0
        last_progress = time.monotonic()
        bar.update(0, 0, 0)
        while queue or any(w.job for w in workers):
            for worker in workers:
                if worker.job is None and queue:
                    worker.start(queue.pop())
                    last_progress = time.monotonic()
            participant.executor.spin_once(timeout_sec=0.01)
            for worker in workers:
                if worker.job is not None and worker.channel.step_arrived():
                    steps += 1
                    last_progress = time.monotonic()
                    result = worker.advance()
                    if result is not None:
                        results.append(result)
                        successes += result.success
                        bar.update(len(results), steps, successes)
            if time.monotonic() - last_progress > timeout:
                stuck = next(w for w in workers if w.job is not None)
                raise stuck.channel.step_lost_error()
    finally:
        participant.close()
    return in_job_order(jobs, results)


def _suite_name(task: str) -> str:
    """`task` in the suite's spelling, from either spelling (any letter case)."""
    from . import _native
    names = {}
    for suite, reference in _native.reference_task_names():
        names[suite.lower()] = suite
        names["/".join(reference).lower()] = suite
    try:
        return names[str(Task.parse(task)).lower()]
    except KeyError:
        raise ValueError(f"task {task!r} is not one of the 256: robot/object/obstacle/objective, "
                         "e.g. IIWA/box/no_obstacle/pick_place or IIWA/Box/None/PickPlace") from None


def evaluate(namespaces: Sequence[str] | None = None, *, backend: str | None = None,
             experiment: str = "default", num_train: int = 0, element: str = "", split_seed: int = 0,
             splits: Sequence[str] = ("train", "test"), max_tasks: int | None = None, episodes: int = 1,
             seed: int = 0, agent: str = "random", use_task_id_obs: bool = True, envs: int | None = None,
             horizon: int = 500, domain_id: int | None = None, timeout: float = 10.0,
             progress: bool = True, tasks: Sequence[str] | None = None
             ) -> tuple[dict[str, list[str]], list[EpisodeResult], list[Metric]]:
    """The protocol as a function: (the split's task lists, every episode, the metrics).
    `tasks` (names in either spelling) replaces the drawn split: they are the train list, and
    the test list is empty.

    `backend`: "native" (in-process, `envs` environments, episodes of at most `horizon` steps)
    or "ros" (the suite's environments in `namespaces`, with the suite's horizon); by default
    "ros" when `namespaces` are given, else "native"."""
    backend = backend or ("ros" if namespaces else "native")
    if backend not in BACKENDS:
        raise ValueError(f"backend {backend!r} is not one of {', '.join(BACKENDS)}")
    if backend == "ros" and not namespaces:
        raise ValueError("the ros backend needs the namespaces of the suite's environments")
    if backend == "native" and namespaces:
        raise ValueError("the native backend runs its own environments: give no namespaces "
                         "(or choose the ros backend)")
    if experiment not in EXPERIMENTS:
        raise ValueError(f"experiment {experiment!r} is not one of {', '.join(EXPERIMENTS)}")
    if episodes < 1:
        raise ValueError("episodes must be at least 1")
    if horizon < 1:
        raise ValueError("horizon must be at least 1")
    agent_factory(agent)  # a bad agent fails now, not after the split was drawn
    unknown = set(splits) - {"train", "test"}
    if unknown or not splits:
        raise ValueError(f"splits {list(splits)}: choose from train, test")
    if tasks:
        lists = {"train": [_suite_name(t) for t in tasks], "test": []}
        splits = ["train"]
    elif backend == "native":
        from . import _native
        train, test = _native.sample_tasks(experiment, num_train, element, split_seed)
        lists = {"train": train, "test": test}
    else:
        lists = sample_split(namespaces[0], experiment, num_train, element, split_seed, domain_id, timeout)
    chosen = {name: lists[name][:max_tasks] if max_tasks else lists[name] for name in splits}
    jobs = [_Job(name, task, seed + j) for name in splits for task in chosen[name] for j in range(episodes)]
    if not jobs:
        raise ValueError(f"the {experiment} split with num_train {num_train} has no {' or '.join(splits)} tasks")
    if backend == "native":
        results = run_episodes_native(jobs, envs, agent, use_task_id_obs=use_task_id_obs, horizon=horizon,
                                      progress=progress)
    else:
        results = run_episodes(jobs, namespaces, agent, use_task_id_obs=use_task_id_obs, domain_id=domain_id,
                               timeout=timeout, progress=progress)
    return lists, results, metrics(results)


def sample_split(namespace: str, experiment: str, num_train: int, element: str, seed: int,
                 domain_id: int | None = None, timeout: float = 10.0) -> dict[str, list[str]]:
    """The reference's train/test lists, from the suite's `sample_tasks` service."""
    from ._link import Channel, Participant
    participant = Participant("composuite_eval_split", domain_id)
    try:
        channel = Channel(participant, namespace, timeout)
        if not participant.spin_for(channel.sample_tasks_client.service_is_ready, channel.discovery_timeout):
            raise SuiteNotRunningError(
                f"no sample_tasks service in namespace {channel.namespace} within {channel.discovery_timeout:g} s: "
                "is `composuite launch` running there, with the same ROS_DOMAIN_ID?")
        train, test = channel.sample_tasks(experiment, num_train, element, seed)
    finally:
        participant.close()
    return {"train": [str(t) for t in train], "test": [str(t) for t in test]}


# ---- output -------------------------------------------------------------------------------------

def table(rows: Sequence[Metric]) -> str:
    lines = [f"{'split':<6} {'axis':<10} {'element':<12} {'tasks':>5} {'episodes':>8} {'R̄':>8} {'S̄':>7}"]
    for m in rows:
        lines.append(f"{m.split:<6} {m.axis:<10} {m.element or '(all)':<12} {m.tasks:>5} {m.episodes:>8} "
                     f"{m.mean_return:>8.3f} {m.success_rate:>7.1%}")
    return "\n".join(lines)


def write_outputs(out: Path, config: dict, lists: dict, results: Sequence[EpisodeResult],
                  rows: Sequence[Metric]) -> list[Path]:
    out.mkdir(parents=True, exist_ok=True)
    written = []
    with open(out / "episodes.csv", "w", newline="") as f:
        writer = csv.writer(f)
        writer.writerow(["split", "task", "seed", "namespace", "episode", "length", "return",
                         "success", "furthest_stage"])
        for r in results:
            writer.writerow([r.split, r.task, r.seed, r.namespace, r.episode, r.length,
                             repr(r.episode_return), int(r.success), r.furthest_stage])
    written.append(out / "episodes.csv")
    with open(out / "summary.csv", "w", newline="") as f:
        writer = csv.writer(f)
        writer.writerow(["split", "axis", "element", "tasks", "episodes", "mean_return", "success_rate"])
        for m in rows:
            writer.writerow([m.split, m.axis, m.element, m.tasks, m.episodes, repr(m.mean_return),
                             repr(m.success_rate)])
    written.append(out / "summary.csv")
    summary = {"config": config, "tasks": lists, "metrics": [asdict(m) for m in rows],
               "episodes": [asdict(r) for r in results]}
    (out / "summary.json").write_text(json.dumps(summary, indent=1))
    written.append(out / "summary.json")
    png = plot(out / "eval.png", rows)
    if png:
        written.append(png)
    return written


def plot(path: Path, rows: Sequence[Metric]) -> Path | None:
    """Success rate and mean return per axis element, train and test side by side."""
    try:
        import matplotlib
        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
    except ImportError:
        print("composuite-eval: matplotlib not installed, no eval.png "
              "(pip install 'composuite_ros[plots]')", file=sys.stderr)
        return None
    splits = list(dict.fromkeys(m.split for m in rows))
    labels = list(dict.fromkeys((m.axis, m.element) for m in rows))
    figure, axes = plt.subplots(2, 1, figsize=(max(6, 0.5 * len(labels) + 2), 6), sharex=True)
    width = 0.8 / len(splits)
    for k, split in enumerate(splits):
        by_label = {(m.axis, m.element): m for m in rows if m.split == split}
        xs = [i + k * width for i, label in enumerate(labels) if label in by_label]
        present = [label for label in labels if label in by_label]
        axes[0].bar(xs, [by_label[lb].success_rate for lb in present], width, label=split)
        axes[1].bar(xs, [by_label[lb].mean_return for lb in present], width, label=split)
    axes[0].set_ylabel("success rate S̄")
    axes[0].set_ylim(0, 1)
    axes[1].set_ylabel("mean return R̄")
    axes[1].set_xticks([i + width * (len(splits) - 1) / 2 for i in range(len(labels))])
    axes[1].set_xticklabels([e or "all" for _, e in labels], rotation=45, ha="right")
    axes[0].legend()
    figure.suptitle("CompoSuite-ROS evaluation")
    figure.tight_layout()
    figure.savefig(path, dpi=100)
    plt.close(figure)
    return path


# ---- command line -------------------------------------------------------------------------------

def parser() -> argparse.ArgumentParser:
    p = argparse.ArgumentParser(prog="composuite-eval", description=__doc__,
                                formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--experiment", default="default", choices=EXPERIMENTS,
                   help="how the split is drawn: default (uniform over the 256 tasks), smallscale "
                        "(the 64 tasks with --element), holdout (train without --element but one)")
    p.add_argument("--num-train", type=int, default=0,
                   help="training tasks: default 0..256, smallscale 0..64, holdout 1..193")
    p.add_argument("--element", default="", help="axis element for smallscale/holdout, e.g. IIWA, plate")
    p.add_argument("--split-seed", type=int, default=0, help="the reference's shuffling_seed")
    p.add_argument("--tasks", nargs="+", default=None, metavar="TASK",
                   help="evaluate these tasks instead of a drawn split (robot/object/obstacle/"
                        "objective, either spelling; reported as the train list)")
    p.add_argument("--splits", default="train,test", help="which lists to run: train, test or train,test")
    p.add_argument("--max-tasks", type=int, default=None,
                   help="run only the first N tasks of each list (quick checks; the metrics then "
                        "cover those tasks only)")
    p.add_argument("--episodes", type=int, default=1, help="episodes per task (episode j: seed --seed + j)")
    p.add_argument("--seed", type=int, default=0, help="seed of each task's first episode")
    p.add_argument("--agent", default="random", help="random, zero, or module:Class with act(observation)")
    p.add_argument("--backend", choices=BACKENDS, default=None,
                   help="native: in-process environments (the default without --namespaces); ros: the "
                        "running suite's environments in --namespaces")
    p.add_argument("--namespaces", default=None,
                   help="comma-separated namespaces of the suite's environments (composuite launch "
                        "--envs N: /env_00,/env_01,...; a plain composuite launch: /); implies --backend ros")
    p.add_argument("--envs", type=int, default=None,
                   help="native: environments stepped together (default: one per core)")
    p.add_argument("--horizon", type=int, default=500,
                   help="native: episode length limit in steps (over ROS the suite's --horizon holds)")
    p.add_argument("--no-task-id-obs", action="store_true", help="77-value observations (no task one-hots)")
    p.add_argument("--timeout", type=float, default=10.0, help="seconds any wait may take")
    p.add_argument("--out", type=Path, default=None, help="output folder (default runs/eval_<unix time>)")
    p.add_argument("--quiet", action="store_true", help="no progress line")
    return p


def main(argv: Sequence[str] | None = None) -> int:
    args = parser().parse_args(argv)
    namespaces = [ns for ns in args.namespaces.split(",") if ns] if args.namespaces is not None else []
    backend = args.backend or ("ros" if args.namespaces is not None else "native")
    if backend == "ros" and not namespaces:
        namespaces = ["/"]
    if args.envs is not None and args.envs < 1:
        print("composuite-eval: --envs must be at least 1", file=sys.stderr)
        return 2
    splits = [s for s in args.splits.split(",") if s]
    out = args.out or Path("runs") / f"eval_{int(time.time())}"
    try:
        lists, results, rows = evaluate(
            namespaces, backend=backend, envs=args.envs, horizon=args.horizon, experiment=args.experiment, num_train=args.num_train, element=args.element,
            split_seed=args.split_seed, splits=splits, max_tasks=args.max_tasks, episodes=args.episodes,
            seed=args.seed, agent=args.agent, use_task_id_obs=not args.no_task_id_obs,
            timeout=args.timeout, progress=not args.quiet, tasks=args.tasks)
    except (ValueError, TimeoutError, RuntimeError) as err:
        print(f"composuite-eval: {err}", file=sys.stderr)
        return 2
    config = {k: (str(v) if isinstance(v, Path) else v) for k, v in vars(args).items()}
    print(table(rows))
    for path in write_outputs(out, config, lists, results, rows):
        print(f"wrote {path}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
