"""Checking a dataset file against the simulation: every episode played again from its seed
with its stored actions must give the stored observations (the same float32 bits), rewards,
flags and final observation."""

from __future__ import annotations

import os
from dataclasses import dataclass
from typing import Callable

import numpy as np

from .. import _native
from .generate import DEFAULT_HORIZON, default_threads
from .layout import DatasetError
from .reader import open_task

# Episodes replayed per call into the core.
EPISODES_PER_CALL = 64
# Keys compared row by row, in the order a difference is looked for.
_COMPARED = ("observations", "rewards", "terminals", "timeouts", "successes")


@dataclass
class Verdict:
    """What `verify` found: `difference` is None when every row matched."""

    path: str
    rows: int
    episodes: int
    difference: str | None

    @property
    def ok(self) -> bool:
        return self.difference is None


def _bits(values: np.ndarray) -> np.ndarray:
    """Values as their bit patterns, so -0.0 differs from 0.0 and NaN equals itself."""
    values = np.ascontiguousarray(values)
    return values.view(np.uint32) if values.dtype == np.float32 else values


def verify(path: str | os.PathLike, *, threads: int | None = None,
           progress: Callable[[str], None] | None = None) -> Verdict:
    """Re-simulate every episode of one file; the first difference is named in the verdict."""
    data = open_task(path)
    if data.task is None or "episode_seeds" not in data.arrays:
        raise DatasetError(f"{data.path} has no task attribute or no episode_seeds: only files "
                           "this suite wrote can be re-simulated")
    horizon = int(data.attrs.get("horizon", DEFAULT_HORIZON))
    episodes = data.episodes()
    if episodes and episodes[0][0] != 0:
        return Verdict(str(data.path), len(data), len(episodes), "episode_starts[0] is not 0")
    successes_rule = np.asarray(data["successes"][:]) == (np.asarray(data["rewards"][:]) == 1.0)
    if not successes_rule.all():
        row = int(np.argmin(successes_rule))
        return Verdict(str(data.path), len(data), len(episodes),
                       f"row {row}: successes is {int(data['successes'][row])} but the reward "
                       f"is {float(data['rewards'][row])!r} (successes must equal rewards == 1)")
    actions = np.asarray(data["actions"][:])
    outside = ~np.isfinite(actions) | (np.abs(actions) > 1.0)
    if outside.any():
        row = int(np.nonzero(outside.any(axis=1))[0][0])
        return Verdict(str(data.path), len(data), len(episodes),
                       f"row {row}: action {actions[row].tolist()} is outside the reference's "
                       "action space [-1, 1]^8")
    del actions
    threads = threads or default_threads()
    finals = np.asarray(data["episode_final_observations"][:])
    for first in range(0, len(episodes), EPISODES_PER_CALL):
        batch = episodes[first:first + EPISODES_PER_CALL]
        lo, hi = batch[0][0], batch[-1][1]
        actions = np.ascontiguousarray(data["actions"][lo:hi], dtype=np.float32)
        starts = np.array([a - lo for a, _, _ in batch], dtype=np.int64)
        seeds = np.array([s for _, _, s in batch], dtype=np.uint64)
        replayed = _native.replay(str(data.task.task), seeds, starts, actions, threads=threads,
                                  horizon=horizon)
        offsets = np.concatenate([[0], np.cumsum(replayed["lengths"])])
        for k, (a, b, seed) in enumerate(batch):
            number = first + k
            where = f"episode {number} (seed {seed}, rows {a}..{b - 1})"
            length = int(replayed["lengths"][k])
            if length != b - a:
                return Verdict(str(data.path), len(data), len(episodes),
                               f"{where}: the simulation ended it after {length} steps, "
                               f"the file holds {b - a} rows")
            r0 = int(offsets[k])
            for key in _COMPARED:
                stored = _bits(np.asarray(data[key][a:b]))
                again = _bits(replayed[key][r0:r0 + length])
                differs = np.nonzero((stored != again).reshape(length, -1).any(axis=1))[0]
                if differs.size:
                    row = a + int(differs[0])
                    return Verdict(str(data.path), len(data), len(episodes),
                                   f"row {row} ({where}, step {row - a}): {key} differ "
                                   f"(stored {np.asarray(data[key][row])!r}, replayed "
                                   f"{replayed[key][r0 + row - a]!r})")
            if not np.array_equal(_bits(finals[number]),
                                  _bits(replayed["episode_final_observations"][k])):
                return Verdict(str(data.path), len(data), len(episodes),
                               f"{where}: episode_final_observations differ")
        if progress:
            progress(f"{data.path}: {hi:,}/{len(data):,} rows replayed, identical so far")
    return Verdict(str(data.path), len(data), len(episodes), None)
