#!/usr/bin/env python3
"""Time ONE task of the original CompoSuite benchmark by the protocol of docs/src/reference-speed.md.

    python bench_reference.py --task IIWA/box/no_obstacle/pick_place [--steps 2000] [--composuite-src DIR]

Runs inside the reference venv (scripts/reference-venv) with an extracted CompoSuite checkout
(commit 1fa36f6) on PYTHONPATH or given as --composuite-src; nothing of the reference is copied
here, it is imported. The caller pins the process to a core (`taskset -c CORE`); BLAS and OpenMP
are limited to one thread below, before numpy is imported. One process times one task:

* the env is built as the benchmark builds it, `composuite.make(robot, obj, obstacle, objective,
  use_task_id_obs=True)` with `make`'s defaults otherwise (joint-position controller, horizon 500,
  shaped rewards, ignore_done, no renderer): 93-value observation, 8-value action;
* warm-up: a reset and --warmup (20) steps;
* then a reset and --steps (2000) steps of uniform random actions in [-1, 1] (drawn beforehand
  from numpy's default_rng(--seed)), resetting every --reset-every (500) steps or when the env
  reports done; episode k starts with `np.random.seed(seed + k)` (the reference's own randomness
  is numpy's global generator).

Prints one JSON line on stdout (everything else goes to stderr):
  task              the task in the port's spelling (ROBOT/object/obstacle/objective)
  steps_per_s       steps / time spent inside `step` only
  loop_steps_per_s  steps / time of the whole timed loop, the resets inside it included
  reset_s           median duration of a reset (all resets of the run, warm-up included)
  build_s           duration of `composuite.make` (it resets the env twice itself)

The task is given in the port's wire spelling (IIWA, Jaco, Gen3, Panda / box, dumbbell, plate,
hollow_box / no_obstacle, object_wall, object_door, goal_wall / pick_place, push, shelf,
trash_can); the reference's own spellings (Kinova3, Hollowbox, None, Trashcan, ...) work too.
"""

import os

# One thread for every math library the reference stack may use; must precede numpy's import.
for _var in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS", "NUMEXPR_NUM_THREADS",
             "NUMBA_NUM_THREADS"):
    os.environ[_var] = "1"

import argparse  # noqa: E402
import contextlib  # noqa: E402
import json  # noqa: E402
import statistics  # noqa: E402
import sys  # noqa: E402
import time  # noqa: E402
import warnings  # noqa: E402

# Port wire name -> the reference's spelling, per axis (the reference's own names map to themselves).
ROBOTS = {"IIWA": "IIWA", "Jaco": "Jaco", "Gen3": "Kinova3", "Panda": "Panda"}
OBJECTS = {"box": "Box", "dumbbell": "Dumbbell", "plate": "Plate", "hollow_box": "Hollowbox"}
OBSTACLES = {"no_obstacle": "None", "object_wall": "ObjectWall", "object_door": "ObjectDoor",
             "goal_wall": "GoalWall"}
OBJECTIVES = {"pick_place": "PickPlace", "push": "Push", "shelf": "Shelf", "trash_can": "Trashcan"}
AXES = [("robot", ROBOTS), ("object", OBJECTS), ("obstacle", OBSTACLES), ("objective", OBJECTIVES)]

OBS_SIZE, ACTION_SIZE = 93, 8


def parse_task(task):
    """'ROBOT/object/obstacle/objective' (either spelling, any case) -> (port name, reference names)."""
    parts = task.split("/")
    if len(parts) != 4:
        raise ValueError(f"task {task!r}: expected ROBOT/object/obstacle/objective")
    port, ref = [], []
    for part, (axis, table) in zip(parts, AXES):
        for wire, reference in table.items():
            if part.lower() in (wire.lower(), reference.lower()):
                port.append(wire)
                ref.append(reference)
                break
        else:
            names = ", ".join(table)
            raise ValueError(f"task {task!r}: unknown {axis} {part!r} (one of {names})")
    return "/".join(port), ref


def timed(fn, *args):
    start = time.perf_counter()
    result = fn(*args)
    return result, time.perf_counter() - start


def run(args):
    import numpy as np

    port_name, (robot, obj, obstacle, objective) = parse_task(args.task)
    if args.composuite_src:
        sys.path.insert(0, os.path.abspath(args.composuite_src))
    warnings.filterwarnings("ignore")  # gym / robosuite deprecation chatter
    # The reference prints to stdout in places; keep stdout for the JSON line.
    with contextlib.redirect_stdout(sys.stderr):
        try:
            import composuite
        except ImportError as err:
            sys.exit(f"bench_reference: cannot import composuite ({err}); put an extracted CompoSuite "
                     "1fa36f6 checkout on PYTHONPATH or pass --composuite-src DIR")

        env, build_s = timed(lambda: composuite.make(robot, obj, obstacle, objective, use_task_id_obs=True))
        if env.observation_space.shape != (OBS_SIZE,) or env.action_space.shape != (ACTION_SIZE,):
            sys.exit(f"bench_reference: unexpected spaces {env.observation_space.shape} / "
                     f"{env.action_space.shape} (want {OBS_SIZE} / {ACTION_SIZE}): not the pinned reference?")

        resets = []
        episode = 0

        def reset():
            nonlocal episode
            np.random.seed(args.seed + episode)
            episode += 1
            resets.append(timed(env.reset)[1])

        rng = np.random.default_rng(args.seed)
        actions = rng.uniform(-1.0, 1.0, size=(args.warmup + args.steps, ACTION_SIZE))
        reset()  # warm-up
        for action in actions[:args.warmup]:
            if env.step(action)[2]:
                reset()

        reset()
        in_episode, stepping = 0, 0.0
        start = time.perf_counter()
        for action in actions[args.warmup:]:
            if in_episode == args.reset_every:
                reset()
                in_episode = 0
            t = time.perf_counter()
            _, _, done, _ = env.step(action)
            stepping += time.perf_counter() - t
            in_episode += 1
            if done:  # robosuite refuses further steps (Push ends an episode when the object is lifted)
                in_episode = args.reset_every
        loop = time.perf_counter() - start
        env.close()

    return {"task": port_name, "steps_per_s": args.steps / stepping, "loop_steps_per_s": args.steps / loop,
            "reset_s": statistics.median(resets), "build_s": build_s}


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--task", required=True, help="ROBOT/object/obstacle/objective")
    parser.add_argument("--steps", type=int, default=2000, help="steps timed (default 2000)")
    parser.add_argument("--warmup", type=int, default=20,
                        help="warm-up steps after the first reset (default 20)")
    parser.add_argument("--reset-every", type=int, default=500, help="steps per episode (default 500)")
    parser.add_argument("--seed", type=int, default=0,
                        help="action stream and first reset seed (default 0)")
    parser.add_argument("--composuite-src", metavar="DIR",
                        help="extracted CompoSuite checkout to import from (else PYTHONPATH)")
    args = parser.parse_args()
    if args.steps < 1 or args.warmup < 0 or args.reset_every < 1:
        parser.error("--steps and --reset-every must be at least 1, --warmup at least 0")
    try:
        parse_task(args.task)
    except ValueError as err:
        parser.error(str(err))
    print(json.dumps(run(args)), flush=True)


if __name__ == "__main__":
    main()
