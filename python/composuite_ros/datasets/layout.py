"""Where datasets live and what they are called: the offline benchmark's folder layout
(`{root}/{type}/{Robot}_{Object}_{Obstacle}_{Objective}/data.hdf5`), its spellings, its dataset
types, and the ways to choose tasks (names, axis filters, the offline repo's split files).

The reference's spellings come from the simulation core's axis tables (one source of truth for
both the suite's names and the reference's).
"""

from __future__ import annotations

import json
import os
from pathlib import Path
from typing import Iterable, NamedTuple, Sequence

from .. import _native
from ..tasks import AXES, Task

DATA_FILE = "data.hdf5"
# What a file is called while it is being written: renamed to DATA_FILE only when whole.
PARTIAL_FILE = "data.hdf5.partial"

# The offline benchmark's dataset types (the folder under the root).
DATASET_TYPES = ("expert", "medium", "random", "medium-replay")
# The types `generate` plays itself (medium-replay is drawn from a learner's run: `subsample`).
GENERATED_TYPES = ("expert", "medium", "random")

AXIS_NAMES = tuple(AXES)  # robot, object, obstacle, objective


class DatasetError(ValueError):
    """Bad input to the dataset tools: the message names what was wrong and what is valid."""


class TaskNames(NamedTuple):
    """One task under both spellings."""

    task: Task                          # the suite's, e.g. IIWA/box/no_obstacle/pick_place
    reference: tuple[str, str, str, str]  # the reference's, e.g. (IIWA, Box, None, PickPlace)

    @property
    def folder(self) -> str:
        """The task's folder name in the offline layout: IIWA_Box_None_PickPlace."""
        return "_".join(self.reference)


def _table() -> list[TaskNames]:
    return [TaskNames(Task.parse(name), tuple(reference))
            for name, reference in _native.reference_task_names()]


TASKS: list[TaskNames] = _table()
_BY_SUITE = {str(t.task): t for t in TASKS}
_BY_REFERENCE = {t.reference: t for t in TASKS}
_BY_FOLDER = {t.folder: t for t in TASKS}
# Each axis's elements, suite spelling → reference spelling, in the suite's order.
_REFERENCE_OF = {axis: {t.task[i]: t.reference[i] for t in TASKS}
                 for i, axis in enumerate(AXIS_NAMES)}
# Each axis's reference spellings, in the suite's order: {"robot": ("IIWA", "Jaco", ...), ...}.
REFERENCE_SPELLINGS = {axis: tuple(names.values()) for axis, names in _REFERENCE_OF.items()}


def names_of(task: str | Task | Sequence[str]) -> TaskNames:
    """A task given as robot/object/obstacle/objective, each part in the suite's spelling
    (`IIWA/box/no_obstacle/pick_place`) or the reference's (`IIWA/Box/None/PickPlace`), any
    case; or as a 4-sequence of those; or as its folder name (`IIWA_Box_None_PickPlace`)."""
    if isinstance(task, str) and "/" not in task and task in _BY_FOLDER:
        return _BY_FOLDER[task]
    parts = tuple(task.split("/")) if isinstance(task, str) else tuple(task)
    if len(parts) != 4:
        raise DatasetError(
            f"task {task!r} is not robot/object/obstacle/objective: give e.g. "
            f"IIWA/box/no_obstacle/pick_place (the suite's spelling) or IIWA/Box/None/PickPlace "
            f"(the reference's)")
    elements = tuple(_element(axis, str(part)) for axis, part in zip(AXIS_NAMES, parts))
    return _BY_SUITE["/".join(elements)]


def select_tasks(tasks: Iterable[str] = (), *, robot: Sequence[str] = (),
                 object: Sequence[str] = (), obstacle: Sequence[str] = (),
                 objective: Sequence[str] = (), split: str | os.PathLike | None = None,
                 split_part: str = "train") -> list[TaskNames]:
    """Tasks by name, by axis filter (each a list of elements in either spelling; a task is kept
    when every filtered axis matches), or from a split file. Without names or a split, the
    filters choose among all 256 (no filter: all 256). Order: as named, else the suite's."""
    chosen: list[TaskNames] = [names_of(t) for t in tasks]
    if split is not None:
        chosen += read_split(split, split_part)
    filters = {"robot": robot, "object": object, "obstacle": obstacle, "objective": objective}
    keep = {axis: {_element(axis, e) for e in values} for axis, values in filters.items() if values}
    pool = chosen if (tasks or split is not None) else TASKS
    picked = [t for t in pool
              if all(t.task.elements()[axis] in allowed for axis, allowed in keep.items())]
    unique = list(dict.fromkeys(picked))
    if not unique:
        raise DatasetError("no task matches the given names, filters and split")
    return unique


def _element(axis: str, name: str) -> str:
    """An axis element in either spelling, any case, as the suite spells it."""
    for suite, reference in _REFERENCE_OF[axis].items():
        if name.lower() in (suite.lower(), reference.lower()):
            return suite
    raise DatasetError(
        f"unknown {axis} {name!r}; valid: {', '.join(AXES[axis])} "
        f"(or the reference's {', '.join(REFERENCE_SPELLINGS[axis])})")


def read_split(path: str | os.PathLike, part: str = "train") -> list[TaskNames]:
    """The tasks of a split file in the offline repo's format: a JSON list of
    `[robot, obj, obstacle, objective]` in the reference's spellings. Also accepted: an object
    whose `part` key (e.g. "train" or "test") holds such a list."""
    path = Path(path)
    try:
        data = json.loads(path.read_text())
    except FileNotFoundError:
        raise DatasetError(f"split file {path} does not exist") from None
    except json.JSONDecodeError as e:
        raise DatasetError(f"split file {path} is not JSON: {e}") from None
    if isinstance(data, dict):
        if part not in data:
            raise DatasetError(f"split file {path} has no {part!r} list; it has {sorted(data)}")
        data = data[part]
    if not isinstance(data, list):
        raise DatasetError(f"split file {path} is not a list of [robot, obj, obstacle, objective]")
    tasks = []
    for i, entry in enumerate(data):
        if not (isinstance(entry, list) and len(entry) == 4 and all(isinstance(e, str) for e in entry)):
            raise DatasetError(f"split file {path}, entry {i}: {entry!r} is not "
                               "[robot, obj, obstacle, objective]")
        for axis, name in zip(AXIS_NAMES, entry):
            if name not in REFERENCE_SPELLINGS[axis]:
                raise DatasetError(
                    f"split file {path}, entry {i}: {axis} {name!r} is not in the reference's "
                    f"spellings; valid: {', '.join(REFERENCE_SPELLINGS[axis])}")
        tasks.append(_BY_REFERENCE[tuple(entry)])
    return tasks


def task_file(root: str | os.PathLike, dataset_type: str, task: TaskNames) -> Path:
    """`{root}/{type}/{Robot}_{Object}_{Obstacle}_{Objective}/data.hdf5`."""
    return Path(root) / dataset_type / task.folder / DATA_FILE


def check_type(dataset_type: str, valid: Sequence[str] = DATASET_TYPES) -> str:
    if dataset_type not in valid:
        raise DatasetError(f"dataset type {dataset_type!r} is unknown; valid: {', '.join(valid)}")
    return dataset_type
