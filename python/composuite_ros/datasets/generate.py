"""Generating datasets: each (task, type) a shard, played inside the simulation core on all
its threads and written in the offline layout.

A shard depends only on its task, type, first seed, row count and horizon — not on the
machine, the thread count or which other shards ran — so a shard run twice (or retried by Ray
after a worker died) comes out bit-identical.
"""

from __future__ import annotations

import os
import shlex
import subprocess
import sys
import time
from dataclasses import dataclass, field
from importlib import metadata
from pathlib import Path
from typing import Callable, Sequence

from .. import _native
from . import medium
from .layout import GENERATED_TYPES, DatasetError, TaskNames, check_type, task_file
from .writer import COMPRESSIONS, DatasetWriter

DEFAULT_TRANSITIONS = 1_000_000
DEFAULT_HORIZON = 500
# Episodes played per call into the core: a progress line each (~16 k rows at most).
EPISODES_PER_CALL = 32
# Marks a file this suite wrote (the authors' loader ignores attributes).
FORMAT = "composuite-ros offline dataset v1"

# Why `generate` does not write a known type itself.
_NOT_GENERATED = {
    "medium-replay": "medium-replay is what a learner saw on its way to medium: record a PPO "
                     "run (examples/ppo_train.py --dataset-out RUN.hdf5) and draw it with "
                     "`composuite-dataset subsample RUN.hdf5`",
}

_EXPERT = ("the planned expert (nodes/core/src/expert/planned/): joint-space plans followed "
           "with the reference's controller")


@dataclass
class Shard:
    """One file to write: a task's dataset of one type."""

    task: TaskNames
    dataset_type: str
    transitions: int = DEFAULT_TRANSITIONS
    first_seed: int = 0
    horizon: int = DEFAULT_HORIZON
    compression: str = "none"
    command: str = ""
    extra_attrs: dict = field(default_factory=dict)
    target_success: float = medium.DEFAULT_TARGET
    medium_table: str = str(medium.TABLE)

    def path(self, root: str | os.PathLike) -> Path:
        return task_file(root, self.dataset_type, self.task)


def suite_provenance() -> dict[str, str]:
    """The suite's version, and the git commit of its checkout when it runs from one (an
    editable install); a `+dirty` suffix when the checkout has changes."""
    try:
        version = metadata.version("composuite_ros")
    except metadata.PackageNotFoundError:
        version = "unknown"
    commit = "unknown (not a git checkout)"
    here = Path(__file__).resolve().parent
    try:
        head = subprocess.run(["git", "-C", str(here), "rev-parse", "HEAD"], capture_output=True,
                              text=True, timeout=10)
        if head.returncode == 0:
            commit = head.stdout.strip()
            dirty = subprocess.run(["git", "-C", str(here), "status", "--porcelain",
                                    "--untracked-files=no"], capture_output=True, text=True,
                                   timeout=10)
            if dirty.stdout.strip():
                commit += "+dirty"
    except (OSError, subprocess.TimeoutExpired):
        pass
    return {"suite_version": version, "suite_commit": commit}


def default_threads() -> int:
    return len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else (os.cpu_count() or 1)


def write_shard(shard: Shard, root: str | os.PathLike, *, threads: int | None = None,
                progress: Callable[[str], None] | None = None) -> Path:
    """Play and write one shard; returns the file's path. The file appears (renamed from its
    temporary name) only when whole."""
    threads = threads or default_threads()
    policy, noise, settings = _policy(shard, threads, progress)
    collector = _native.Collector(str(shard.task.task), policy, noise=noise,
                                  first_seed=shard.first_seed, threads=threads,
                                  horizon=shard.horizon)
    attrs = {
        "format": FORMAT,
        **suite_provenance(),
        "task": str(shard.task.task),
        "task_reference": "_".join(shard.task.reference),
        "dataset_type": shard.dataset_type,
        "policy": policy,
        "policy_settings": settings,
        "horizon": shard.horizon,
        "first_seed": shard.first_seed,
        "transitions": shard.transitions,
        "compression": shard.compression,
        "creation_command": shard.command,
        **shard.extra_attrs,
    }
    folder = shard.path(root).parent
    started = time.monotonic()
    with DatasetWriter(folder, shard.transitions, attrs, shard.compression) as writer:
        while writer.written < shard.transitions:
            chunk = collector.collect(EPISODES_PER_CALL, shard.transitions - writer.written)
            writer.add(chunk)
            if progress:
                elapsed = max(time.monotonic() - started, 1e-9)
                progress(f"{shard.dataset_type}/{shard.task.folder}: {writer.written:,}/"
                         f"{shard.transitions:,} rows, {writer.written / elapsed:,.0f} rows/s")
        return writer.close()


def _policy(shard: Shard, threads: int, progress: Callable[[str], None] | None
            ) -> tuple[str, float, dict]:
    """The core's policy that plays `shard`'s type, its noise, and the settings the file's
    attributes record."""
    if shard.dataset_type == "random":
        return "random", 0.0, {"actions": "uniform in [-1, 1] per value, float32",
                               "rng": "MT19937 keyed by the task index and the episode's seed"}
    if shard.dataset_type == "expert":
        return "expert", 0.0, {"expert": _EXPERT, "actions": "the reference's 8 numbers, float32",
                               "noise": 0.0, "expert_revision": medium.EXPERT_REVISION}
    if shard.dataset_type == "medium":
        calibration, source = medium.noise_for(shard.task, shard.target_success, shard.horizon,
                                               table=shard.medium_table, threads=threads,
                                               progress=progress)
        return "expert", calibration.noise, {
            "expert": _EXPERT, "actions": "the reference's 8 numbers, float32",
            "expert_revision": medium.EXPERT_REVISION,
            "noise": calibration.noise,
            "noise_on": "each of the 7 joint values: Gaussian of this standard deviation, then "
                        "clipped to [-1, 1]; the gripper value is the expert's",
            "rng": "MT19937 keyed by the task index and the episode's seed",
            "target_success": calibration.target,
            "calibrated_success": calibration.success,
            "expert_success": calibration.expert_success,
            "calibration_episodes": calibration.episodes,
            "calibration_first_seed": calibration.first_seed,
            "calibration_source": source,
        }
    raise DatasetError(f"cannot generate {shard.dataset_type!r} data: "
                       f"{_NOT_GENERATED.get(shard.dataset_type, 'unknown type')}")


def plan(root: str | os.PathLike, tasks: Sequence[TaskNames], types: Sequence[str], *,
         transitions: int = DEFAULT_TRANSITIONS, first_seed: int = 0,
         horizon: int = DEFAULT_HORIZON, compression: str = "none", overwrite: bool = False,
         resume: bool = False, command: str = "", target_success: float = medium.DEFAULT_TARGET,
         medium_table: str | os.PathLike = medium.TABLE) -> list[Shard]:
    """The shards to write, after checking every input (nothing is written here). With
    `resume`, shards whose `data.hdf5` already exists are left out; otherwise an output folder
    that already holds files is refused unless `overwrite`."""
    if not isinstance(transitions, int) or transitions <= 0:
        raise DatasetError(f"transitions must be a positive whole number; got {transitions!r}")
    if horizon <= 0:
        raise DatasetError(f"horizon must be a positive number of steps; got {horizon}")
    if not 0 <= first_seed <= 2**32 - 1:
        raise DatasetError(f"seed {first_seed} is outside the reference's 0..{2**32 - 1}")
    if compression not in COMPRESSIONS:
        raise DatasetError(f"compression {compression!r} is unknown; valid: "
                           f"{', '.join(COMPRESSIONS)}")
    for t in types:
        check_type(t)
        if t not in GENERATED_TYPES:
            raise DatasetError(f"cannot generate {t!r} data: {_NOT_GENERATED[t]}")
    if "medium" in types:
        medium.check_target(target_success)
        if Path(medium_table).exists():
            medium.NoiseTable.load(medium_table)      # refuses a file that is not a table
        elif Path(medium_table) != medium.TABLE:
            raise DatasetError(f"medium noise table {medium_table} does not exist")
    if overwrite and resume:
        raise DatasetError("--overwrite and --resume exclude each other: overwrite rewrites "
                           "every file, resume keeps the finished ones")
    root = Path(root)
    if root.exists() and not root.is_dir():
        raise DatasetError(f"output {root} exists and is not a folder")
    if root.is_dir() and any(root.iterdir()) and not (overwrite or resume):
        raise DatasetError(f"output {root} already holds files; pass --overwrite to replace "
                           "them or --resume to finish the missing ones")
    shards = [Shard(task, t, transitions, first_seed, horizon, compression, command,
                    target_success=target_success, medium_table=str(medium_table))
              for t in types for task in tasks]
    if resume:
        shards = [s for s in shards if not s.path(root).exists()]
    return shards


def generate(root: str | os.PathLike, tasks: Sequence[TaskNames], types: Sequence[str] = ("random",),
             *, transitions: int = DEFAULT_TRANSITIONS, first_seed: int = 0,
             horizon: int = DEFAULT_HORIZON, threads: int | None = None,
             compression: str = "none", overwrite: bool = False, resume: bool = False,
             progress: Callable[[str], None] | None = None, command: str | None = None,
             ray_address: str | None = None, target_success: float = medium.DEFAULT_TARGET,
             medium_table: str | os.PathLike = medium.TABLE) -> list[Path]:
    """Write every (task, type) shard under `root`: on this machine one after another, each on
    `threads` threads (default: every core); with `ray_address`, as Ray tasks of `threads` CPUs
    (default 1) on that cluster. `medium` files take their noise for `target_success` from
    `medium_table`, or calibrate it first where the table has none. Returns the files
    written."""
    command = command if command is not None else shlex.join([Path(sys.argv[0]).name, *sys.argv[1:]])
    shards = plan(root, tasks, types, transitions=transitions, first_seed=first_seed,
                  horizon=horizon, compression=compression, overwrite=overwrite, resume=resume,
                  command=command, target_success=target_success, medium_table=medium_table)
    if ray_address is not None:
        from .cluster import generate_on_ray
        return generate_on_ray(ray_address, root, shards, threads=threads or 1,
                               progress=progress)
    return [write_shard(s, root, threads=threads, progress=progress) for s in shards]


__all__ = ["DEFAULT_TRANSITIONS", "Shard", "generate", "plan", "write_shard", "suite_provenance"]
