"""`composuite tasks --split ...` against CPython itself.

The reference benchmark draws its train/test splits with CPython's global `random` module
(docs/src/reference-facts.md §7.2). `composuite_ros.compat.sample_tasks` is that algorithm
written out in Python from that description, run with CPython's own `random`; its lists
(reference names mapped to wire names) must equal the JSON of the `composuite` binary (the Rust
implementation) for many seeds, every experiment, every element and several sizes. Two
implementations in two languages, each from the description, checking each other.
"""

from __future__ import annotations

import json
import os
import subprocess
from pathlib import Path

import pytest

from composuite_ros import compat

REPO = Path(__file__).resolve().parents[2]

# The reference's sampling lists, in its order (§7.2 step 2).
ROBOTS = ["IIWA", "Jaco", "Kinova3", "Panda"]
OBJECTS = ["Box", "Dumbbell", "Plate", "Hollowbox"]
OBSTACLES = ["None", "GoalWall", "ObjectDoor", "ObjectWall"]
OBJECTIVES = ["PickPlace", "Push", "Shelf", "Trashcan"]

WIRE = {
    "IIWA": "IIWA", "Jaco": "Jaco", "Kinova3": "Gen3", "Panda": "Panda",
    "Box": "box", "Dumbbell": "dumbbell", "Plate": "plate", "Hollowbox": "hollow_box",
    "None": "no_obstacle", "GoalWall": "goal_wall", "ObjectDoor": "object_door",
    "ObjectWall": "object_wall",
    "PickPlace": "pick_place", "Push": "push", "Shelf": "shelf", "Trashcan": "trash_can",
}


def reference_split(experiment: str, num_train: int, element: str | None, seed: int,
                    no_shuffle: bool = False) -> tuple[list[tuple], list[tuple]]:
    """§7.2 with reference names, using CPython's `random`: `composuite_ros.compat`'s
    `sample_tasks`, the reference's algorithm written in Python (state saved and restored)."""
    return compat.sample_tasks(experiment, num_train, smallscale_elem=element, holdout_elem=element,
                               shuffling_seed=seed, no_shuffle=no_shuffle)


def wire(task: tuple) -> str:
    return "/".join(WIRE[name] for name in task)


def composuite_path() -> Path:
    """The `composuite` binary: $COMPOSUITE_BIN, else the cargo target directory's debug build."""
    path = os.environ.get("COMPOSUITE_BIN")
    if not path:
        target = Path(os.environ.get("CARGO_TARGET_DIR", REPO / "target"))
        path = str(target / "debug" / "composuite")
    if not Path(path).is_file():
        raise FileNotFoundError(
            f"{path} not found: build it with `cargo build -p composuite` or set COMPOSUITE_BIN"
        )
    return Path(path)


def composuite_split(experiment: str, num_train: int, element: str | None, seed: int,
                     no_shuffle: bool = False) -> dict:
    args = [str(composuite_path()), "tasks", "--split", experiment, "--num-train", str(num_train),
            "--seed", str(seed), "--json"]
    if element is not None:
        args += ["--element", element]
    if no_shuffle:
        args.append("--no-shuffle")
    result = subprocess.run(args, capture_output=True, text=True, check=False)
    assert result.returncode == 0, f"{' '.join(args)} failed: {result.stderr}"
    return json.loads(result.stdout)


def check(experiment: str, num_train: int, element: str | None, seed: int,
          no_shuffle: bool = False) -> None:
    train, test = reference_split(experiment, num_train, element, seed, no_shuffle)
    got = composuite_split(experiment, num_train, element, seed, no_shuffle)
    assert got == {"train": [wire(t) for t in train], "test": [wire(t) for t in test]}, (
        experiment, num_train, element, seed, no_shuffle)


SEEDS = [*range(50), 1234, 2**31 - 1, 2**32 - 1, 2**32, 2**40 + 7, 2**63 + 5, 2**64 - 1]


@pytest.mark.parametrize("seed", SEEDS)
def test_default(seed: int) -> None:
    for num_train in (0, 1, 56, 255, 256):
        check("default", num_train, None, seed)


# Every element of every axis, in reference spellings on purpose (the CLI accepts them).
ELEMENTS = ROBOTS + OBJECTS + OBSTACLES + OBJECTIVES


@pytest.mark.parametrize("seed", SEEDS[::3])
@pytest.mark.parametrize("element", ELEMENTS)
def test_smallscale(seed: int, element: str) -> None:
    for num_train in (0, 1, 32, 64):
        check("smallscale", num_train, element, seed)


@pytest.mark.parametrize("seed", SEEDS[::3])
@pytest.mark.parametrize("element", ELEMENTS)
def test_holdout(seed: int, element: str) -> None:
    for num_train in (1, 2, 56, 193):
        check("holdout", num_train, element, seed)


@pytest.mark.parametrize("experiment,element", [("default", None), ("smallscale", "Jaco"),
                                                ("holdout", "GoalWall")])
def test_no_shuffle_is_the_reference_order(experiment: str, element: str | None) -> None:
    check(experiment, 10, element, 3, no_shuffle=True)


def test_wire_spellings_give_the_same_split() -> None:
    assert composuite_split("holdout", 40, "gen3", 7) == composuite_split(
        "holdout", 40, "Kinova3", 7)
    assert composuite_split("smallscale", 9, "no_obstacle", 7) == composuite_split(
        "smallscale", 9, "None", 7)

