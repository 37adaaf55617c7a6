"""The benchmark's four axes and task names, in the suite's wire spelling.

A task is `robot/object/obstacle/objective`, e.g. `IIWA/box/no_obstacle/pick_place`. The suite
also accepts the reference's spellings (`Kinova3`, `PickPlace`, ...) case-insensitively; the
`set_task` service is the judge, and its error lists the valid choices.
"""

from __future__ import annotations

import itertools
from typing import NamedTuple

ROBOTS = ("IIWA", "Jaco", "Gen3", "Panda")
OBJECTS = ("box", "hollow_box", "plate", "dumbbell")
OBSTACLES = ("no_obstacle", "object_wall", "object_door", "goal_wall")
OBJECTIVES = ("pick_place", "push", "trash_can", "shelf")
AXES = {"robot": ROBOTS, "object": OBJECTS, "obstacle": OBSTACLES, "objective": OBJECTIVES}


class Task(NamedTuple):
    robot: str
    object: str
    obstacle: str
    objective: str

    def __str__(self) -> str:
        return "/".join(self)

    @classmethod
    def parse(cls, task: str | tuple | Task) -> Task:
        """`R/O/B/J` (or a 4-tuple) as a Task; a ValueError naming the expected form otherwise.
        Spellings are checked by the suite (`set_task`), which knows every accepted alias."""
        parts = tuple(task) if not isinstance(task, str) else tuple(task.split("/"))
        if len(parts) != 4 or not all(isinstance(p, str) and p for p in parts):
            raise ValueError(
                f"task {task!r} is not robot/object/obstacle/objective, "
                f"e.g. {ROBOTS[0]}/{OBJECTS[0]}/{OBSTACLES[0]}/{OBJECTIVES[0]}")
        return cls(*parts)

    @classmethod
    def of_spec(cls, spec) -> Task:
        """A composuite_msgs/TaskSpec (what the suite's services answer) as a Task."""
        return cls(spec.robot, spec.object, spec.obstacle, spec.objective)

    def elements(self) -> dict[str, str]:
        """The axis element of each axis: {"robot": "IIWA", ...}."""
        return dict(zip(AXES, self))


def all_tasks() -> list[Task]:
    """The 256 tasks in the suite's axis order."""
    return [Task(*t) for t in itertools.product(ROBOTS, OBJECTS, OBSTACLES, OBJECTIVES)]
