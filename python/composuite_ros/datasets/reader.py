"""Reading datasets without loading them into RAM.

An uncompressed file (what `generate` writes by default) stores each key contiguously, so its
arrays are memory-mapped: the operating system pages rows in as they are touched, and many
tasks' worth of data costs address space, not memory. A gzip file is read through h5py, chunk
by chunk, as slices are asked for.
"""

from __future__ import annotations

import json
import os
from dataclasses import dataclass
from pathlib import Path
from typing import Iterator, Sequence

import numpy as np

from .layout import DATA_FILE, DatasetError, TaskNames, names_of, task_file
from .writer import ROW_KEYS, _h5py

EPISODE_KEYS = ("episode_starts", "episode_seeds", "episode_final_observations")


@dataclass
class TaskData:
    """One task's file: its arrays (memory-mapped numpy arrays, or h5py datasets for a
    compressed file — both slice like numpy), its attributes and where it is."""

    path: Path
    task: TaskNames | None
    arrays: dict
    attrs: dict
    mapped: bool
    # The open h5py file behind a compressed file's datasets (None when memory-mapped).
    handle: object = None

    def __len__(self) -> int:
        return len(self.arrays["rewards"])

    def __getitem__(self, key: str):
        return self.arrays[key]

    def episodes(self) -> list[tuple[int, int, int]]:
        """`(first row, end row, seed)` of each episode (files this suite wrote)."""
        if "episode_starts" not in self.arrays:
            raise DatasetError(f"{self.path} has no episode_starts: not a file this suite wrote")
        starts = np.asarray(self.arrays["episode_starts"])
        seeds = np.asarray(self.arrays["episode_seeds"])
        ends = np.append(starts[1:], len(self))
        return [(int(a), int(b), int(s)) for a, b, s in zip(starts, ends, seeds)]

    def episode_successes(self) -> np.ndarray:
        """Whether each episode has a successful step (bool, one per episode; files this suite
        wrote)."""
        if "episode_starts" not in self.arrays:
            raise DatasetError(f"{self.path} has no episode_starts: not a file this suite wrote")
        starts = np.asarray(self.arrays["episode_starts"])
        if not len(starts):
            return np.zeros(0, bool)
        return np.maximum.reduceat(np.asarray(self.arrays["successes"]), starts) > 0


def _attr(value):
    if isinstance(value, bytes):
        value = value.decode()
    if isinstance(value, str) and value[:1] in "[{":
        try:
            return json.loads(value)
        except json.JSONDecodeError:
            return value
    return value.item() if isinstance(value, np.generic) else value


def open_task(path: str | os.PathLike) -> TaskData:
    """Open one `data.hdf5` (or the folder holding it) for reading."""
    h5py = _h5py()
    path = Path(path)
    if path.is_dir():
        path = path / DATA_FILE
    if not path.exists():
        raise DatasetError(f"{path} does not exist")
    try:
        file = h5py.File(path, "r")
    except OSError as e:
        raise DatasetError(f"{path} is not an HDF5 file: {e}") from None
    missing = [k for k in ("observations", "actions", "rewards", "terminals", "timeouts")
               if k not in file]
    if missing:
        file.close()
        raise DatasetError(f"{path} lacks {', '.join(missing)}: not an offline dataset file")
    attrs = {k: _attr(v) for k, v in file.attrs.items()}
    arrays: dict = {}
    mapped = True
    for key in [*ROW_KEYS, *EPISODE_KEYS]:
        if key not in file:
            continue
        data = file[key]
        offset = data.id.get_offset()
        if offset is None or data.compression is not None or data.chunks is not None:
            arrays[key] = data
            mapped = False
        elif data.size == 0:
            arrays[key] = np.zeros(data.shape, data.dtype)
        else:
            arrays[key] = np.memmap(path, dtype=data.dtype, mode="r", offset=offset,
                                    shape=data.shape)
    if mapped:
        file.close()
    task = None
    try:
        task = names_of(attrs.get("task") or path.parent.name)
    except DatasetError:
        pass
    return TaskData(path, task, arrays, attrs, mapped, None if mapped else file)


class OfflineDataset:
    """Many tasks' files read as one dataset (row i of the whole is row j of one task, tasks in
    the given order), without copying them into memory."""

    def __init__(self, parts: Sequence[TaskData]):
        if not parts:
            raise DatasetError("no dataset files to read")
        self.parts = list(parts)
        self.offsets = np.cumsum([0] + [len(p) for p in self.parts])

    def __len__(self) -> int:
        return int(self.offsets[-1])

    @property
    def tasks(self) -> list[TaskNames | None]:
        return [p.task for p in self.parts]

    def rows(self, index: np.ndarray, keys: Sequence[str] = tuple(ROW_KEYS)) -> dict:
        """The rows at `index` (whole-dataset row numbers), as numpy arrays per key."""
        index = np.asarray(index, dtype=np.int64)
        if index.size and (index.min() < 0 or index.max() >= len(self)):
            raise IndexError(f"rows outside 0..{len(self) - 1}")
        part_of = np.searchsorted(self.offsets, index, side="right") - 1
        out = {}
        for key in keys:
            first = self.parts[0][key]
            out[key] = np.empty((len(index), *first.shape[1:]), dtype=first.dtype)
        for p in np.unique(part_of):
            where = np.nonzero(part_of == p)[0]
            local = index[where] - self.offsets[p]
            for key in keys:
                data = self.parts[p][key]
                if isinstance(data, np.ndarray):  # memory-mapped
                    out[key][where] = data[local]
                else:  # h5py takes rising, distinct indices
                    unique, inverse = np.unique(local, return_inverse=True)
                    out[key][where] = data[unique][inverse]
        return out

    def sample(self, batch_size: int, rng: np.random.Generator | None = None,
               keys: Sequence[str] = tuple(ROW_KEYS)) -> dict:
        """A batch of rows drawn uniformly from every task together."""
        rng = rng or np.random.default_rng()
        return self.rows(rng.integers(0, len(self), size=batch_size), keys)

    def chunks(self, rows: int = 65_536, keys: Sequence[str] = tuple(ROW_KEYS)
               ) -> Iterator[tuple[TaskData, dict]]:
        """Every row once, in order, as `(task file, {key: rows})` slices of at most `rows`."""
        for part in self.parts:
            for start in range(0, len(part), rows):
                yield part, {k: np.asarray(part[k][start:start + rows]) for k in keys}


def load(root: str | os.PathLike, dataset_type: str, tasks: Sequence | None = None
         ) -> OfflineDataset:
    """The files of `dataset_type` (a folder under `root`: expert, medium, random,
    medium-replay, or a name of yours) for `tasks` (any spelling; default: every task folder
    present), read lazily."""
    if tasks is None:
        folder = Path(root) / dataset_type
        if not folder.is_dir():
            raise DatasetError(f"{folder} does not exist")
        paths = sorted(p for p in folder.glob(f"*/{DATA_FILE}"))
        if not paths:
            raise DatasetError(f"{folder} holds no */{DATA_FILE}")
    else:
        paths = [task_file(root, dataset_type, names_of(t)) for t in tasks]
    return OfflineDataset([open_task(p) for p in paths])


def to_d3rlpy(dataset: OfflineDataset):
    """A d3rlpy 2.x `MDPDataset` of every row (copied into memory: d3rlpy keeps its own
    arrays). Timeouts are cleared where a terminal is set, as the authors' loader does."""
    try:
        import d3rlpy
    except ImportError:
        raise DatasetError("to_d3rlpy needs d3rlpy 2.x: pip install 'composuite_ros[d3rlpy]'") from None
    keys = ("observations", "actions", "rewards", "terminals", "timeouts")
    columns = {k: np.concatenate([np.asarray(p[k][:]) for p in dataset.parts]) for k in keys}
    timeouts = columns["timeouts"].copy()
    timeouts[columns["terminals"] == 1] = 0
    return d3rlpy.dataset.MDPDataset(
        observations=columns["observations"], actions=columns["actions"],
        rewards=columns["rewards"], terminals=columns["terminals"].astype(np.float32),
        timeouts=timeouts.astype(np.float32))
