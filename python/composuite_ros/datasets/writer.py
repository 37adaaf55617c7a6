"""Writing one task's dataset file in the offline benchmark's layout.

A file is written under a temporary name and renamed to `data.hdf5` only once every row is in,
so an interrupted run never leaves a `data.hdf5` that looks complete. Its row count is fixed
when it is created (the authors' loader expects exactly that many rows), which also lets an
uncompressed file store each key contiguously: `load` then reads it by memory-mapping.

Keys: `observations` (N, 93) float32, `actions` (N, 8) float32, `rewards` (N,) float32,
`terminals`, `timeouts`, `successes` (N,) uint8 — what the authors' `get_datasets` reads —
and what it ignores: `episode_starts` (first row of each episode, int64), `episode_seeds` (the
seed `CompoSuiteNative-v0`'s `reset(seed=...)` starts it with, uint64) and
`episode_final_observations` (E, 93) float32, the observation after each episode's last step —
no row holds it, and a Minari episode needs it.
"""

from __future__ import annotations

import json
import os
from pathlib import Path
from typing import Any, Mapping

import numpy as np

from .layout import DATA_FILE, PARTIAL_FILE, DatasetError

OBSERVATION_SIZE = 93
ACTION_SIZE = 8
# Key → (dtype, shape of one row).
ROW_KEYS: dict[str, tuple[type, tuple[int, ...]]] = {
    "observations": (np.float32, (OBSERVATION_SIZE,)),
    "actions": (np.float32, (ACTION_SIZE,)),
    "rewards": (np.float32, ()),
    "terminals": (np.uint8, ()),
    "timeouts": (np.uint8, ()),
    "successes": (np.uint8, ()),
}
COMPRESSIONS = ("none", "gzip")


def _h5py():
    try:
        import h5py
    except ImportError:
        raise DatasetError("writing and reading datasets needs h5py: "
                           "pip install 'composuite_ros[datasets]'") from None
    return h5py


class DatasetWriter:
    """Rows of one task, appended episode by episode, into `folder/data.hdf5`.

    Args:
        folder: the task's folder (`{root}/{type}/{Robot}_{Object}_{Obstacle}_{Objective}`).
        rows: the file's row count N; `close()` refuses a file with fewer rows written.
        attrs: file attributes (provenance); values that are not str/int/float are stored as
            JSON text.
        compression: "none" (contiguous keys, memory-mappable) or "gzip".
    """

    def __init__(self, folder: str | os.PathLike, rows: int, attrs: Mapping[str, Any] = (),
                 compression: str = "none"):
        if rows <= 0:
            raise DatasetError(f"a dataset file needs at least 1 row; got {rows}")
        if compression not in COMPRESSIONS:
            raise DatasetError(f"compression {compression!r} is unknown; valid: "
                               f"{', '.join(COMPRESSIONS)}")
        h5py = _h5py()
        self.folder = Path(folder)
        self.folder.mkdir(parents=True, exist_ok=True)
        self.path = self.folder / DATA_FILE
        self.partial = self.folder / PARTIAL_FILE
        self.rows = rows
        self.written = 0
        self._starts: list[np.ndarray] = []
        self._seeds: list[np.ndarray] = []
        self._finals: list[np.ndarray] = []
        self._file = h5py.File(self.partial, "w")
        options: dict[str, Any] = {}
        if compression == "gzip":
            options = {"compression": "gzip", "compression_opts": 4, "shuffle": True}
        for key, (dtype, shape) in ROW_KEYS.items():
            chunks = (min(rows, 10_000), *shape) if options else None
            self._file.create_dataset(key, shape=(rows, *shape), dtype=dtype, chunks=chunks,
                                      **options)
        for key, value in dict(attrs).items():
            if isinstance(value, np.generic):
                value = value.item()
            self._file.attrs[key] = value if isinstance(value, (str, int, float)) \
                else json.dumps(value)

    def add(self, chunk: Mapping[str, np.ndarray]) -> None:
        """Append whole episodes: the row keys, `episode_starts` (relative to the chunk's first
        row), `episode_seeds` and `episode_final_observations`."""
        n = len(chunk["rewards"])
        if self.written + n > self.rows:
            raise DatasetError(f"{self.path}: {self.written} + {n} rows exceed the file's "
                               f"{self.rows}")
        for key, (dtype, shape) in ROW_KEYS.items():
            values = np.asarray(chunk[key])
            if values.dtype != dtype or values.shape != (n, *shape):
                raise DatasetError(f"{key}: {values.dtype} {values.shape}, expected "
                                   f"{np.dtype(dtype)} {(n, *shape)}")
            self._file[key][self.written:self.written + n] = values
        starts = np.asarray(chunk["episode_starts"], dtype=np.int64)
        if n and (len(starts) == 0 or starts[0] != 0):
            raise DatasetError("a chunk must begin with an episode (episode_starts[0] == 0)")
        self._starts.append(starts + self.written)
        seeds = np.asarray(chunk["episode_seeds"], dtype=np.uint64)
        finals = np.asarray(chunk["episode_final_observations"], dtype=np.float32)
        if not (len(seeds) == len(starts) == len(finals)):
            raise DatasetError(f"{len(starts)} episode starts, {len(seeds)} seeds and "
                               f"{len(finals)} final observations: one of each per episode")
        self._seeds.append(seeds)
        self._finals.append(finals.reshape(len(finals), OBSERVATION_SIZE))
        self.written += n

    def close(self) -> Path:
        """Write the episode index and rename the file to `data.hdf5`; returns its path."""
        if self.written != self.rows:
            self.abort()
            raise DatasetError(f"{self.path}: {self.written} of {self.rows} rows written")
        self._file.create_dataset("episode_starts", data=np.concatenate(self._starts))
        self._file.create_dataset("episode_seeds", data=np.concatenate(self._seeds))
        self._file.create_dataset("episode_final_observations",
                                  data=np.concatenate(self._finals))
        self._file.attrs["episodes"] = sum(len(s) for s in self._starts)
        self._file.close()
        os.replace(self.partial, self.path)
        return self.path

    def abort(self) -> None:
        """Drop the unfinished file."""
        if self._file:
            self._file.close()
        self.partial.unlink(missing_ok=True)

    def __enter__(self) -> DatasetWriter:
        return self

    def __exit__(self, kind, value, traceback) -> None:
        if kind is not None and self.partial.exists():
            self.abort()
