#!/usr/bin/env python3
"""Record reference episodes from the original CompoSuite benchmark as JSON test data.

This script runs the *original* Python benchmark (CompoSuite on robosuite 1.4.0 / MuJoCo 2.3.7)
and writes what it observes to gzip-compressed JSON files that the Rust port's tests compare
against. It is not part of the port and never runs in CI: it needs a Python 3.11 environment with
the reference stack installed and a CompoSuite checkout on PYTHONPATH. `scripts/reference-data`
sets both up; see tests/reference/README.md for the file formats.

Five independent parts (select one with --only):

  step0         every one of the 256 tasks x seeds 0..4: the observation right after reset and
                the raw state behind it (joint angles, object pose, grip site, hand frame).
  trajectories  16 tasks x seeds 0, 1: 100 steps of a fixed, closed-form action sequence, with
                observation, reward, success, grasp flag, staged rewards and raw state per step.
  random        the same 16 tasks: episodes of uniformly random actions; per episode the return,
                the success flags and the length.
  spin          each object resting on bin 1's floor, turned by a torque about the vertical for
                1 s: its yaw per control step (how much the contacts' torsional friction resists).
  grasp         the port's scripted plans (data/grasp_plans.json.gz: joint targets and gripper
                actions of 12 tasks x 2 seeds) played through the reference's controller with a
                closed-loop law: object and grip site, grasp flag and reward per plan step, and
                the first successful step (grasp, carry, push and release in MuJoCo's contacts).

All numbers are rounded to 7 decimals. Integral values are written without a decimal point.
"""

import argparse
import datetime
import gzip
import hashlib
import itertools
import json
import math
import os
import platform
import sys
import time
import warnings

# The reference stack prints deprecation chatter (gym, robosuite macros) that would drown the
# progress lines; none of it matters for the recorded numbers.
warnings.filterwarnings("ignore")

# numpy (and the reference stack) are imported in main() after argument parsing, so that --help
# works with any Python 3.
np = None

GENERATOR_VERSION = 1

# CompoSuite commit the data was recorded from. The source tree is an extracted archive (no .git),
# so the commit cannot be read from it; --composuite-commit overrides this value and the meta also
# stores a hash of the Python sources so a different checkout is detectable.
DEFAULT_COMPOSUITE_COMMIT = "1fa36f67f31aeccc9ef75748bfc797960e044a86"

# ------------------------------------------------------------------------------------------------
# Task axes. Reference spellings (what composuite.make accepts) in the order of composuite's
# AVAILABLE_* lists, i.e. the order of its unshuffled task enumeration, and the port's spellings.
# ------------------------------------------------------------------------------------------------
ROBOTS = ["IIWA", "Jaco", "Kinova3", "Panda"]
OBJECTS = ["Box", "Dumbbell", "Plate", "Hollowbox"]
OBSTACLES = ["None", "GoalWall", "ObjectDoor", "ObjectWall"]
OBJECTIVES = ["PickPlace", "Push", "Shelf", "Trashcan"]

PORT_ROBOT = {"IIWA": "IIWA", "Jaco": "Jaco", "Kinova3": "Gen3", "Panda": "Panda"}
PORT_OBJECT = {"Box": "box", "Dumbbell": "dumbbell", "Plate": "plate", "Hollowbox": "hollow_box"}
PORT_OBSTACLE = {
    "None": "no_obstacle",
    "GoalWall": "goal_wall",
    "ObjectDoor": "object_door",
    "ObjectWall": "object_wall",
}
PORT_OBJECTIVE = {"PickPlace": "pick_place", "Push": "push", "Shelf": "shelf", "Trashcan": "trashcan"}

# Names of the values returned by each sub-task's staged_rewards(), in return order, copied from
# the `return r_... ` statements of composuite/tasks/*_subtask.py.
STAGE_NAMES = {
    "PickPlace": ["reach", "grasp", "lift", "hover", "drop"],
    "Push": ["reach", "grasp", "approach"],
    "Shelf": ["reach", "grasp", "lift", "align", "approach"],
    "Trashcan": ["reach", "grasp", "lift", "hover", "drop"],
}

STEP0_SEEDS = [0, 1, 2, 3, 4]
TRAJECTORY_SEEDS = [0, 1]
TRAJECTORY_STEPS = 100
RANDOM_STEPS = 500
RANDOM_RNG_OFFSET = 1000

# Observation layout of the flattened 93-value vector (use_task_id_obs=True). Each group is one
# key of CompoSuite's Gym wrapper, in wrapper order; inside a group the observables appear in
# registration order. Checked against the wrapper's own key positions at runtime.
OBS_LAYOUT = [
    ("object-state", [("obj_pos", 3), ("obj_quat", 4), ("obj_to_eef_pos", 3), ("obj_to_eef_quat", 4)]),
    ("obstacle-state", [("obstacle_pos", 3), ("obstacle_quat", 4), ("obstacle_to_eef_pos", 3),
                        ("obstacle_to_eef_quat", 4)]),
    ("goal-state", [("goal_pos", 3), ("goal_quat", 4), ("goal_to_eef_pos", 3), ("goal_to_eef_quat", 4),
                    ("obj_to_goal", 3)]),
    ("object_id", [("object_id", 4)]),
    ("robot_id", [("robot_id", 4)]),
    ("obstacle_id", [("obstacle_id", 4)]),
    ("subtask_id", [("subtask_id", 4)]),
    ("robot0_proprio-state", [("joint_pos_cos", 7), ("joint_pos_sin", 7), ("joint_vel", 7), ("eef_pos", 3),
                              ("eef_quat", 4), ("gripper_qpos", 2), ("gripper_qvel", 2)]),
]

ACTION_FORMULA = (
    "for step t = 0..99 (0-based, the action applied after observation t): "
    "a[j] = 0.3 * sin(2*pi*t/40 + 0.9*j) for arm joints j = 0..6, evaluated in IEEE f64 as "
    "0.3 * sin(((2.0 * pi) * t) / 40.0 + 0.9 * j) with libm sin (Python math.sin; Rust f64::sin); "
    "a[7] = -1.0 if (t // 25) % 2 == 0 else 1.0 (gripper: open for t in 0..24 and 50..74, close otherwise)"
)

RANDOM_ACTION_RULE = (
    "episode e (0-based) of a task: np.random.seed(e); obs = env.reset(); "
    "rng = np.random.default_rng(1000 + e); then each step a = rng.uniform(-1.0, 1.0, size=8) "
    "(numpy PCG64; uniform = -1 + 2 * ((next_uint64 >> 11) * 2**-53)), env.step(a), for 500 steps "
    "or until the env reports done (Push lift termination)."
)


# ------------------------------------------------------------------------------------------------
# Small helpers
# ------------------------------------------------------------------------------------------------
def log(msg):
    """Progress line on stderr (stdout stays clean)."""
    print(f"[{time.strftime('%H:%M:%S')}] {msg}", file=sys.stderr, flush=True)


def r7(x):
    """Round a number / array / nested list for JSON: floats to 7 decimals, and floats that are
    then integral (one-hots, exact zeros, -0.0) as plain ints to keep the files small."""
    if isinstance(x, (bool, np.bool_)):
        return bool(x)
    if isinstance(x, (int, np.integer)):
        return int(x)
    if isinstance(x, (float, np.floating)):
        v = round(float(x), 7)
        if not math.isfinite(v):
            raise ValueError(f"non-finite value {x!r} in recorded data")
        return int(v) if v == int(v) else v
    if isinstance(x, np.ndarray):
        return [r7(v) for v in x.tolist()]
    if isinstance(x, (list, tuple)):
        return [r7(v) for v in x]
    if x is None:
        return None
    raise TypeError(f"cannot serialise {type(x)}")


def port_name(robot, obj, obstacle, objective):
    return f"{PORT_ROBOT[robot]}/{PORT_OBJECT[obj]}/{PORT_OBSTACLE[obstacle]}/{PORT_OBJECTIVE[objective]}"


def task_record(robot, obj, obstacle, objective):
    """Identity of a task in both spellings plus its index in composuite's unshuffled enumeration
    (64*robot + 16*object + 4*obstacle + objective over the AVAILABLE_* orders above)."""
    return {
        "name": port_name(robot, obj, obstacle, objective),
        "reference": {"robot": robot, "object": obj, "obstacle": obstacle, "objective": objective},
        "reference_index": 64 * ROBOTS.index(robot) + 16 * OBJECTS.index(obj)
        + 4 * OBSTACLES.index(obstacle) + OBJECTIVES.index(objective),
    }


def all_tasks():
    return list(itertools.product(ROBOTS, OBJECTS, OBSTACLES, OBJECTIVES))


TASK_DESIGN = (
    "16 tasks; task i (0..15): robot = ROBOTS[i // 4], object = OBJECTS[i % 4], "
    "obstacle = OBSTACLES[(i // 4 + i % 4) % 4], objective = OBJECTIVES[(i // 4 + 2 * (i % 4) + i // 8) % 4] "
    "with ROBOTS = [IIWA, Jaco, Kinova3, Panda], OBJECTS = [Box, Dumbbell, Plate, Hollowbox], "
    "OBSTACLES = [None, GoalWall, ObjectDoor, ObjectWall], OBJECTIVES = [PickPlace, Push, Shelf, Trashcan]; "
    "every element of every axis appears exactly 4 times"
)


def design_tasks():
    """The 16-task design used by the trajectory and random parts (see TASK_DESIGN); the
    4-times-per-element balance is asserted."""
    tasks = []
    for i in range(16):
        r, o = i // 4, i % 4
        tasks.append((ROBOTS[r], OBJECTS[o], OBSTACLES[(r + o) % 4], OBJECTIVES[(r + 2 * o + i // 8) % 4]))
    for axis, names in enumerate([ROBOTS, OBJECTS, OBSTACLES, OBJECTIVES]):
        for name in names:
            count = sum(1 for t in tasks if t[axis] == name)
            assert count == 4, f"task design: {name} appears {count} times"
    return tasks


def trajectory_action(t):
    """The fixed action of step t (see ACTION_FORMULA). math.sin, not np.sin: numpy may use its
    own vectorised sin, math.sin is the C library's, which Rust's f64::sin also calls."""
    arm = [0.3 * math.sin(2.0 * math.pi * t / 40.0 + 0.9 * j) for j in range(7)]
    grip = -1.0 if (t // 25) % 2 == 0 else 1.0
    return np.array(arm + [grip], dtype=np.float64)


def filter_tasks(tasks, patterns):
    """Keep the tasks whose port or reference name contains any of the patterns (case-insensitive)."""
    if not patterns:
        return tasks
    pats = [p.strip().lower() for p in patterns.split(",") if p.strip()]
    kept = []
    for t in tasks:
        names = (port_name(*t).lower(), "/".join(t).lower())
        if any(p in n for p in pats for n in names):
            kept.append(t)
    return kept


# ------------------------------------------------------------------------------------------------
# Reading state out of the reference env
# ------------------------------------------------------------------------------------------------
class Reference:
    """Thin accessor around a composuite Gym env. robosuite rebuilds the MjSim on every reset
    (hard_reset=True), so the sim must be re-read from the env each time, never cached."""

    def __init__(self, composuite, robot, obj, obstacle, objective):
        self.objective = objective
        self.gym = composuite.make(
            robot, obj, obstacle, objective,
            use_task_id_obs=True, has_renderer=False, has_offscreen_renderer=False, ignore_done=True,
        )
        self.env = self.gym.env  # the robosuite (CompositionalEnv subclass) environment

    def close(self):
        self.gym.close()

    def reset(self, seed):
        np.random.seed(seed)
        return self.gym.reset()

    @property
    def sim(self):
        return self.env.sim

    def raw_state(self):
        """Raw MuJoCo quantities behind the observation, read straight from MjData (which is what
        the observables read too: after a step, body/site positions come from the kinematics
        MuJoCo computed at the start of the last 2 ms substep, while qpos/qvel are post-step)."""
        env, data, model = self.env, self.sim.data, self.sim.model
        robot = env.robots[0]
        hand = robot.robot_model.eef_name
        hand_id = model.body_name2id(hand)
        xquat = np.array(data.body_xquat[env.obj_body_id])
        hand_quat = np.array(data.body_xquat[hand_id])
        return {
            "arm_qpos": np.array([data.qpos[i] for i in robot._ref_joint_pos_indexes]),
            "arm_qvel": np.array([data.qvel[i] for i in robot._ref_joint_vel_indexes]),
            "gripper_qpos": np.array([data.qpos[i] for i in robot._ref_gripper_joint_pos_indexes]),
            "object_pos": np.array(data.body_xpos[env.obj_body_id]),
            "object_quat_xyzw": xquat[[1, 2, 3, 0]],
            "grip_site_pos": np.array(data.site_xpos[robot.eef_site_id]),
            "hand_rot": np.array(data.body_xmat[hand_id]).reshape(3, 3),
            "eef_quat_xyzw": hand_quat[[1, 2, 3, 0]],
        }

    def fresh_kinematics(self):
        """Grip site and object pose recomputed with mj_kinematics from the *current* qpos on a
        scratch MjData (what a simulator that refreshes kinematics after integrating would report)."""
        import mujoco

        model = self.sim.model._model
        scratch = mujoco.MjData(model)
        scratch.qpos[:] = self.sim.data._data.qpos
        scratch.mocap_pos[:] = self.sim.data._data.mocap_pos
        scratch.mocap_quat[:] = self.sim.data._data.mocap_quat
        mujoco.mj_kinematics(model, scratch)
        robot = self.env.robots[0]
        q = scratch.xquat[self.env.obj_body_id]
        return {
            "grip_site_pos": np.array(scratch.site_xpos[robot.eef_site_id]),
            "object_pos": np.array(scratch.xpos[self.env.obj_body_id]),
            "object_quat_xyzw": np.array([q[1], q[2], q[3], q[0]]),
        }

    def grasp(self):
        """The grasp test exactly as every sub-task's staged_rewards() calls it."""
        env = self.env
        return bool(env._check_grasp(gripper=env.robots[0].gripper,
                                     object_geoms=[g for g in env.object.contact_geoms]))

    def success(self):
        return bool(self.env._check_success())

    def staged(self, action):
        """staged_rewards(action) after _check_success() has refreshed the in-bin/in-shelf/in-can
        flags the stages are gated on (the env's own reward() calls them in that order)."""
        self.env._check_success()
        return [float(v) for v in self.env.staged_rewards(action)]


def obs_layout_meta(ref):
    """Observation layout (names and [start, end) index ranges), checked against the wrapper."""
    groups, fields, idx = [], [], 0
    for key, parts in OBS_LAYOUT:
        start = idx
        for name, size in parts:
            fields.append({"name": name, "group": key, "start": idx, "end": idx + size})
            idx += size
        groups.append({"name": key, "start": start, "end": idx})
        positions = ref.gym.observation_positions[key]
        assert positions[0] == start and positions[-1] + 1 == idx, f"layout mismatch for {key}"
    assert idx == ref.gym.obs_dim == 93, f"expected 93 observation values, got {ref.gym.obs_dim}"
    return {"size": idx, "groups": groups, "fields": fields,
            "quaternion_order": "xyzw",
            "one_hot_orders": {
                "object_id": ["Box", "Dumbbell", "Plate", "Hollowbox"],
                "robot_id": ["IIWA", "Jaco", "Panda", "Kinova3"],
                "obstacle_id": ["None", "ObjectWall", "ObjectDoor", "GoalWall"],
                "subtask_id": ["PickPlace", "Push", "Shelf", "Trashcan"],
            }}


def composuite_source_hash(composuite):
    """sha256 over composuite/**/*.py (sorted relative paths + contents)."""
    root = os.path.dirname(composuite.__file__)
    h = hashlib.sha256()
    for dirpath, dirnames, filenames in os.walk(root):
        dirnames.sort()
        for fn in sorted(filenames):
            if fn.endswith(".py"):
                path = os.path.join(dirpath, fn)
                h.update(os.path.relpath(path, root).encode())
                with open(path, "rb") as f:
                    h.update(f.read())
    return h.hexdigest()


# ------------------------------------------------------------------------------------------------
# Spin: torsional friction, measured
# ------------------------------------------------------------------------------------------------
SPIN_TORQUES = [0.003, 0.01, 0.02, 0.05, 0.1, 0.2, 0.5, 1.0, 1.5, 2.0, 2.5]  # N*m about world z
SPIN_SETTLE_STEPS = 10  # zero-action control steps before the torque
SPIN_TORQUE_STEPS = 20  # control steps (1 s) with the torque on
SPIN_AFTER_STEPS = 10  # control steps after it is removed
SPIN_RULE = (
    "IIWA/<object>/None/PickPlace, np.random.seed(0); reset(); 10 steps of the all-zero action; then "
    "data.xfrc_applied[object body] = (0, 0, 0, 0, 0, torque) (a torque about world z at the body's "
    "centre of mass) for 20 steps and 0 for 10 more, all-zero actions throughout. yaw[k] is the "
    "object's rotation about world z after step k of those 30 (atan2 of its x axis, unwrapped), "
    "relative to its yaw before the torque; z_end its origin's height after the last step")


def yaw_of(quat_wxyz):
    w, x, y, z = (float(v) for v in quat_wxyz)
    return math.atan2(2.0 * (w * z + x * y), 1.0 - 2.0 * (y * y + z * z))


def run_spin(args, composuite):
    t_start = time.time()
    patterns = [p.lower() for p in args.tasks.split(",")] if args.tasks else []
    objects = [o for o in OBJECTS if not patterns or any(p in o.lower() for p in patterns)]
    records = []
    for obj in objects:
        ref = Reference(composuite, "IIWA", obj, "None", "PickPlace")
        for torque in SPIN_TORQUES:
            ref.reset(0)
            zero = np.zeros(8)
            for _ in range(SPIN_SETTLE_STEPS):
                ref.gym.step(zero)
            body = ref.env.obj_body_id
            data = ref.sim.data
            previous = yaw_of(data.body_xquat[body])
            turned, yaws = 0.0, []
            for k in range(SPIN_TORQUE_STEPS + SPIN_AFTER_STEPS):
                data.xfrc_applied[body, :] = 0.0
                data.xfrc_applied[body, 5] = torque if k < SPIN_TORQUE_STEPS else 0.0
                ref.gym.step(zero)
                now = yaw_of(data.body_xquat[body])
                turned += (now - previous + math.pi) % (2.0 * math.pi) - math.pi
                previous = now
                yaws.append(r7(turned))
            data.xfrc_applied[body, :] = 0.0
            rec = task_record("IIWA", obj, "None", "PickPlace")
            rec.update({"seed": 0, "torque": torque, "yaw": yaws,
                        "z_end": r7(float(data.body_xpos[body][2]))})
            records.append(rec)
            log(f"spin: {rec['name']} torque {torque}: yaw after 1 s {yaws[SPIN_TORQUE_STEPS - 1]:+.4f} rad")
        ref.close()
    meta = base_meta(args, composuite, "spin")
    meta.update({
        "rule": SPIN_RULE,
        "torques": SPIN_TORQUES,
        "settle_steps": SPIN_SETTLE_STEPS,
        "torque_steps": SPIN_TORQUE_STEPS,
        "after_steps": SPIN_AFTER_STEPS,
        "elapsed_seconds": round(time.time() - t_start, 1),
    })
    write_json(os.path.join(args.out, "spin.json"), {"meta": meta, "records": records})


def grasp_action(targets, gripper, obs):
    """The plan's closed-loop law (the port's tests/reference/mod.rs `tracking_action`): each
    joint's wrapped error to its target over the controller's 0.05 rad per unit, clipped."""
    action = np.zeros(8)
    for j in range(7):
        q = math.atan2(obs[68 + j], obs[61 + j])
        error = (targets[j] - q + math.pi) % (2.0 * math.pi) - math.pi
        action[j] = min(1.0, max(-1.0, error / 0.05))
    action[7] = gripper
    return action


def run_grasp(args, composuite):
    with gzip.open(args.grasp_plans, "rt") as f:
        plans = json.load(f)
    hold = plans["meta"]["hold"]
    # The port writes Trashcan as trash_can (it reads both spellings).
    by_name = {port_name(*t).replace("trashcan", "trash_can"): t for t in all_tasks()}
    patterns = [p.lower() for p in args.tasks.split(",")] if args.tasks else []
    t_start = time.time()
    episodes = []
    for plan in plans["episodes"]:
        if patterns and not any(p in plan["name"].lower() for p in patterns):
            continue
        robot, obj, obstacle, objective = by_name[plan["name"]]
        ref = Reference(composuite, robot, obj, obstacle, objective)
        obs = ref.reset(plan["seed"])
        cols = {k: [] for k in ["object_pos", "grip_site_pos", "grasp", "reward"]}
        first_success, step, stopped = None, 0, False
        for targets, gripper in zip(plan["targets"], plan["gripper"]):
            for _ in range(hold):
                obs, reward, done, _info = ref.gym.step(grasp_action(targets, gripper, obs))
                step += 1
                if first_success is None and ref.success():
                    first_success = step
                if step % hold == 0:
                    cols["object_pos"].append(r7(obs[0:3]))
                    cols["grip_site_pos"].append(r7(obs[82:85]))
                    cols["grasp"].append(ref.grasp())
                    cols["reward"].append(r7(reward))
                if done:  # Push's lift rule: the reference refuses the next step
                    stopped = True
                    break
            if stopped:
                break
        ref.close()
        rec = task_record(robot, obj, obstacle, objective)
        rec.update({"seed": plan["seed"], "steps": step, "first_success_step": first_success, **cols})
        episodes.append(rec)
        log(f"grasp: {len(episodes)}/{len(plans['episodes'])} {rec['name']} seed {plan['seed']}: "
            f"{step} steps, first success at {first_success}, grasped in "
            f"{sum(cols['grasp'])}/{len(cols['grasp'])} samples ({time.time() - t_start:.0f}s)")
    meta = base_meta(args, composuite, "grasp")
    meta.update({
        "plans": "tests/reference/data/grasp_plans.json.gz (sha256 "
                 + hashlib.sha256(open(args.grasp_plans, "rb").read()).hexdigest() + ")",
        "hold": hold,
        "law": plans["meta"]["law"],
        "fields": {
            "object_pos": "obs object position after the last control step of each plan step",
            "grip_site_pos": "obs eef_pos at the same samples",
            "grasp": "env._check_grasp(...) at the same samples",
            "reward": "reward returned by that step",
            "first_success_step": "1-based control step whose env._check_success() first held (null: never)",
            "steps": "control steps played (fewer than len(targets) * hold if Push's lift rule ended it)",
        },
        "elapsed_seconds": round(time.time() - t_start, 1),
    })
    write_json_gz(os.path.join(args.out, "grasp.json.gz"), {"meta": meta, "episodes": episodes})


def base_meta(args, composuite, part):
    import gym
    import mujoco
    import numba
    import robosuite

    return {
        "part": part,
        "generator": "tests/reference/generate.py",
        "generator_version": GENERATOR_VERSION,
        "date_utc": datetime.datetime.now(datetime.timezone.utc).strftime("%Y-%m-%dT%H:%M:%SZ"),
        "versions": {
            "python": platform.python_version(),
            "robosuite": robosuite.__version__,
            "mujoco": mujoco.__version__,
            "numpy": np.__version__,
            "numba": numba.__version__,
            "gym": gym.__version__,
        },
        "composuite_commit": args.composuite_commit,
        "composuite_source_sha256": composuite_source_hash(composuite),
        "make_kwargs": {"use_task_id_obs": True, "has_renderer": False, "has_offscreen_renderer": False,
                        "ignore_done": True, "controller": "joint (default)", "env_horizon": "500 (default)",
                        "reward_shaping": "True (default)"},
        "seeding": "np.random.seed(seed) immediately before env.reset(); the env is built once per task",
        "rounding": "floats rounded to 7 decimals; integral values written as ints",
        "task_filter": args.tasks,
    }


def write_json(path, payload):
    """Plain, indented JSON (the small files, meant to be read by people too)."""
    with open(path, "w") as f:
        json.dump(payload, f, indent=1, allow_nan=False)
        f.write("\n")
    log(f"wrote {path} ({os.path.getsize(path)} bytes)")


def write_json_gz(path, payload):
    """Compact gzip JSON with a fixed gzip timestamp, so reruns only differ where data differ."""
    raw = json.dumps(payload, separators=(",", ":"), allow_nan=False).encode()
    with open(path, "wb") as f:
        with gzip.GzipFile(filename="", mode="wb", fileobj=f, mtime=0, compresslevel=9) as gz:
            gz.write(raw)
    log(f"wrote {path} ({os.path.getsize(path)} bytes, {len(raw)} uncompressed)")


def load_partial(path, resume, part, keep=lambda rec: True):
    """The task records an interrupted run appended to `path` (one JSON line per finished task),
    by task name, when resuming (only those `keep` accepts); otherwise the file is removed and the
    run starts afresh."""
    done = {}
    if resume and os.path.exists(path):
        with open(path) as f:
            for line in f:
                rec = json.loads(line)
                if keep(rec):
                    done[rec["name"]] = rec
        log(f"{part}: resuming, {len(done)} tasks already recorded in {path}")
    elif os.path.exists(path):
        os.remove(path)
    return done


# ------------------------------------------------------------------------------------------------
# Part a: observation right after reset, all tasks
# ------------------------------------------------------------------------------------------------
def run_step0(args, composuite):
    tasks = filter_tasks(all_tasks(), args.tasks)
    partial_path = os.path.join(args.out, ".step0.partial.jsonl")
    done = load_partial(partial_path, args.resume, "step0")

    layout = None
    t_start = time.time()
    n_new = 0
    with open(partial_path, "a") as partial:
        for k, (robot, obj, obstacle, objective) in enumerate(tasks):
            rec = task_record(robot, obj, obstacle, objective)
            if rec["name"] in done:
                continue
            ref = Reference(composuite, robot, obj, obstacle, objective)
            if layout is None:
                layout = obs_layout_meta(ref)
            seeds = []
            for seed in STEP0_SEEDS:
                obs = ref.reset(seed)
                state = ref.raw_state()
                seeds.append({"seed": seed, "obs": r7(obs),
                              **{key: r7(value.reshape(-1)) for key, value in state.items()
                                 if key != "arm_qvel"}})
            ref.close()
            rec["seeds"] = seeds
            partial.write(json.dumps(rec, separators=(",", ":")) + "\n")
            partial.flush()
            done[rec["name"]] = rec
            n_new += 1
            elapsed = time.time() - t_start
            eta = elapsed / n_new * (len(tasks) - len(done))
            log(f"step0: {len(done)}/{len(tasks)} {rec['name']} ({elapsed:.0f}s, eta {eta:.0f}s)")

    if layout is None:  # everything came from the partial file: build one env for the layout
        ref = Reference(composuite, *tasks[0])
        layout = obs_layout_meta(ref)
        ref.close()
    meta = base_meta(args, composuite, "step0")
    meta.update({
        "seeds": STEP0_SEEDS,
        "observation_layout": layout,
        "per_seed_fields": {
            "obs": "the 93-value observation returned by reset()",
            "arm_qpos": "qpos of the 7 arm joints, radians, robot joint order",
            "gripper_qpos": "qpos of the 2 RethinkGripper finger slide joints, (l_finger_joint, r_finger_joint) as in the obs, metres",
            "object_pos": "world position of the object body origin (MjData.xpos)",
            "object_quat_xyzw": "world orientation of the object body, xyzw",
            "grip_site_pos": "world position of the gripper's grip_site (= obs eef_pos)",
            "hand_rot": "world rotation matrix of the arm's hand body (robot0_right_hand), 3x3 row-major (MjData.xmat)",
            "eef_quat_xyzw": "hand body world orientation, xyzw (= obs eef_quat)",
        },
        "elapsed_seconds": round(time.time() - t_start, 1),
    })
    ordered = [done[port_name(*t)] for t in tasks]
    write_json_gz(os.path.join(args.out, "step0.json.gz"), {"meta": meta, "tasks": ordered})
    os.remove(partial_path)


# ------------------------------------------------------------------------------------------------
# Part b: fixed-action trajectories
# ------------------------------------------------------------------------------------------------
def run_trajectories(args, composuite):
    tasks = filter_tasks(design_tasks(), args.tasks)
    actions = [trajectory_action(t) for t in range(TRAJECTORY_STEPS)]
    episodes, layout = [], None
    t_start = time.time()
    for robot, obj, obstacle, objective in tasks:
        ref = Reference(composuite, robot, obj, obstacle, objective)
        if layout is None:
            layout = obs_layout_meta(ref)
        for seed in TRAJECTORY_SEEDS:
            rec = task_record(robot, obj, obstacle, objective)
            rec["design_index"] = design_tasks().index((robot, obj, obstacle, objective))
            rec["seed"] = seed
            rec["stage_names"] = STAGE_NAMES[objective]
            cols = {k: [] for k in ["obs", "reward", "success", "grasp", "staged", "done", "arm_qpos",
                                    "arm_qvel", "gripper_qpos", "object_pos", "object_quat_xyzw",
                                    "grip_site_pos", "hand_z"]}
            fresh = {"grip_site_pos": [], "object_pos": [], "object_quat_xyzw": []}

            def record(obs, reward, done, action_for_stages):
                state = ref.raw_state()
                cols["obs"].append(r7(obs))
                cols["reward"].append(r7(reward))
                cols["success"].append(ref.success())
                cols["grasp"].append(ref.grasp())
                cols["staged"].append(r7(ref.staged(action_for_stages)))
                cols["done"].append(bool(done))
                for key in ["arm_qpos", "arm_qvel", "gripper_qpos", "object_pos", "object_quat_xyzw",
                            "grip_site_pos"]:
                    cols[key].append(r7(state[key]))
                cols["hand_z"].append(r7(state["hand_rot"][:, 2]))
                for key, value in ref.fresh_kinematics().items():
                    fresh[key].append(r7(value))

            obs = ref.reset(seed)
            # At reset there is no reward; stages are evaluated with an all-zero action (only the
            # Trashcan "drop" stage reads the action, via action[-1] < 0).
            record(obs, None, False, np.zeros(8))
            stopped_at, stop_reason = None, None
            for t, action in enumerate(actions):
                try:
                    obs, reward, done, _info = ref.gym.step(action.copy())
                except ValueError as err:  # "executing action in terminated episode"
                    stopped_at, stop_reason = t, str(err)
                    break
                record(obs, reward, done, action)
            rec.update({
                "records": len(cols["obs"]),
                "stopped_at_step": stopped_at,
                "stop_reason": stop_reason,
                **cols,
                "fresh_kinematics": fresh,
            })
            episodes.append(rec)
            log(f"trajectories: {len(episodes)}/{2 * len(tasks)} {rec['name']} seed {seed}: "
                f"{rec['records']} records, final reward {cols['reward'][-1]}"
                + (f", stopped at step {stopped_at}" if stopped_at is not None else "")
                + f" ({time.time() - t_start:.0f}s)")
        ref.close()

    meta = base_meta(args, composuite, "trajectories")
    meta.update({
        "seeds": TRAJECTORY_SEEDS,
        "steps": TRAJECTORY_STEPS,
        "task_design": TASK_DESIGN,
        "design_tasks": [port_name(*t) for t in design_tasks()],
        "action_formula": ACTION_FORMULA,
        # The actions exactly as applied (full f64 precision, not rounded) so the port can check
        # its own evaluation of the formula.
        "actions": [a.tolist() for a in actions],
        "observation_layout": layout,
        "record_convention": (
            "record 0 is the state right after reset (reward null, done false, stages evaluated with "
            "a zero action); record t+1 is the state after env.step(actions[t]). If the env refuses "
            "a step (Push termination: done was true), the episode stops there: stopped_at_step is "
            "the index t of the refused action and stop_reason the exception text."
        ),
        "fields": {
            "obs": "93-value observation",
            "reward": "reward returned by step (shaped; 1.0 iff success)",
            "success": "env._check_success() evaluated after the step",
            "grasp": "env._check_grasp(gripper=robot.gripper, object_geoms=object.contact_geoms), the test the staged rewards use",
            "staged": "env.staged_rewards(action) after _check_success(); names in stage_names; reward = max(staged) unless success",
            "done": "done returned by step (only Push sets it: object z - 0.8 > 0.1)",
            "arm_qpos": "7 arm joint angles (rad), post-step MjData.qpos",
            "arm_qvel": "7 arm joint velocities (rad/s), post-step MjData.qvel",
            "gripper_qpos": "2 finger slide joints (l_finger_joint, r_finger_joint), m",
            "object_pos": "object body world position as MjData.xpos holds it (kinematics of the start of the last substep)",
            "object_quat_xyzw": "object body world orientation (MjData.xquat, as xyzw)",
            "grip_site_pos": "grip_site world position (MjData.site_xpos; = obs eef_pos)",
            "hand_z": "third column of the hand body's world rotation matrix (its local z axis in world), MjData.xmat",
            "fresh_kinematics": "grip_site_pos / object_pos / object_quat_xyzw recomputed by mj_kinematics from the post-step qpos (one substep newer than the fields above)",
        },
        "elapsed_seconds": round(time.time() - t_start, 1),
    })
    write_json_gz(os.path.join(args.out, "trajectories.json.gz"), {"meta": meta, "episodes": episodes})


# ------------------------------------------------------------------------------------------------
# Part c: random-action returns
# ------------------------------------------------------------------------------------------------
def run_random(args, composuite):
    tasks = filter_tasks(design_tasks(), args.tasks)
    # Finished tasks are appended to a partial file, so --resume can continue an interrupted run
    # (same mechanism as step0).
    partial_path = os.path.join(args.out, ".random.partial.jsonl")
    finished = load_partial(partial_path, args.resume, "random",
                            keep=lambda rec: len(rec["episodes"]) == args.episodes)
    partial = open(partial_path, "a")
    t_start = time.time()
    n_new = 0
    for k, (robot, obj, obstacle, objective) in enumerate(tasks):
        if port_name(robot, obj, obstacle, objective) in finished:
            continue
        ref = Reference(composuite, robot, obj, obstacle, objective)
        rec = task_record(robot, obj, obstacle, objective)
        rec["design_index"] = design_tasks().index((robot, obj, obstacle, objective))
        rec["episodes"] = []
        for e in range(args.episodes):
            ref.reset(e)
            rng = np.random.default_rng(RANDOM_RNG_OFFSET + e)
            total, hit_one, hit_check, length, terminated, first_action = 0.0, False, False, 0, False, None
            for _ in range(RANDOM_STEPS):
                action = rng.uniform(-1.0, 1.0, size=8)
                if first_action is None:
                    first_action = action.tolist()
                _obs, reward, done, _info = ref.gym.step(action)
                total += reward
                length += 1
                hit_one = hit_one or bool(reward == 1.0)  # reward is a numpy float
                hit_check = hit_check or ref.success()
                if done:
                    terminated = True
                    break
            rec["episodes"].append({
                "episode": e,
                "return": r7(total),
                "success_reward": hit_one,
                "success_check": hit_check,
                "length": length,
                "terminated": terminated,
                "first_action": first_action,  # full precision, to check the port's PCG64 stream
            })
        ref.close()
        partial.write(json.dumps(rec, separators=(",", ":")) + "\n")
        partial.flush()
        finished[rec["name"]] = rec
        n_new += 1
        returns = [ep["return"] for ep in rec["episodes"]]
        elapsed = time.time() - t_start
        log(f"random: {len(finished)}/{len(tasks)} {rec['name']}: mean return {np.mean(returns):.3f} "
            f"({elapsed:.0f}s, eta {elapsed / n_new * (len(tasks) - len(finished)):.0f}s)")
    partial.close()
    results = [finished[port_name(*t)] for t in tasks]

    meta = base_meta(args, composuite, "random")
    meta.update({
        "episodes_per_task": args.episodes,
        "steps_per_episode": RANDOM_STEPS,
        "action_rule": RANDOM_ACTION_RULE,
        "task_design": TASK_DESIGN,
        "fields": {
            "return": "sum of the step rewards",
            "success_reward": "some step reward == 1.0",
            "success_check": "env._check_success() true after some step",
            "length": "steps taken (500 unless terminated)",
            "terminated": "the env reported done (Push lift termination) and the episode ended early",
            "first_action": "the first action of the episode, full precision",
        },
        "elapsed_seconds": round(time.time() - t_start, 1),
    })
    write_json(os.path.join(args.out, "random_returns.json"), {"meta": meta, "tasks": results})
    os.remove(partial_path)


# ------------------------------------------------------------------------------------------------
def main():
    here = os.path.dirname(os.path.abspath(__file__))
    parser = argparse.ArgumentParser(
        description=(
            "Record reference data from the original CompoSuite (robosuite 1.4.0, MuJoCo 2.3.7) for "
            "the Rust port's tests. Needs the reference stack importable (composuite on PYTHONPATH); "
            "scripts/reference-data prepares that and forwards its arguments here. Parts, in the order "
            "they run: trajectories (16 tasks x 2 seeds x 100 fixed steps, ~2 min), step0 (256 tasks x "
            "5 seeds, reset observations, ~40 min: every make/reset recompiles the model), random "
            "(16 tasks x N random-action episodes of 500 steps, ~2 min per episode per 16 tasks), spin "
            "(4 objects x 11 torques, ~2 min), grasp (24 scripted episodes of 2,000 steps, ~15 min)."),
        epilog="Outputs: OUT/trajectories.json.gz, OUT/step0.json.gz, OUT/random_returns.json, OUT/spin.json, "
               "OUT/grasp.json.gz. "
               "See tests/reference/README.md for the formats.",
    )
    parser.add_argument("--out", default=os.path.join(here, "data"),
                        help="output folder (default: the data/ folder next to this script)")
    parser.add_argument("--only", choices=["step0", "trajectories", "random", "spin", "grasp"],
                        help="run only this part (default: all five)")
    parser.add_argument("--tasks", default=None,
                        help="comma-separated case-insensitive substrings; keep only tasks whose port name "
                             "(e.g. Gen3/hollow_box/goal_wall/shelf) or reference name "
                             "(e.g. Kinova3/Hollowbox/GoalWall/Shelf) contains one. Filtered runs write "
                             "incomplete files: point --out elsewhere.")
    parser.add_argument("--episodes", type=int, default=10,
                        help="random part: episodes per task (default 10)")
    parser.add_argument("--resume", action="store_true",
                        help="step0 / random: continue from OUT/.step0.partial.jsonl or "
                             "OUT/.random.partial.jsonl left by an interrupted run")
    parser.add_argument("--grasp-plans", default=os.path.join(here, "data", "grasp_plans.json.gz"),
                        help="grasp part: the plans to play (default: %(default)s, written by the port's "
                             "`cargo run --release -p composuite_core --example reference_grasp -- --write-plans`)")
    parser.add_argument("--composuite-commit", default=DEFAULT_COMPOSUITE_COMMIT,
                        help="CompoSuite commit recorded in the meta (default: %(default)s)")
    args = parser.parse_args()

    global np
    import numpy as np  # noqa: F811
    import composuite

    os.makedirs(args.out, exist_ok=True)
    parts = [args.only] if args.only else ["trajectories", "step0", "random", "spin", "grasp"]
    for part in parts:
        t0 = time.time()
        log(f"part {part}: start")
        {"step0": run_step0, "trajectories": run_trajectories, "random": run_random,
         "spin": run_spin, "grasp": run_grasp}[part](args, composuite)
        log(f"part {part}: done in {time.time() - t0:.0f}s")


if __name__ == "__main__":
    main()
