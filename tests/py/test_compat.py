"""`composuite_ros.compat`, the reference benchmark's own API (`make`, `sample_tasks`) in-process:
its documented usage (make, the reset/step loop to `done`, the wrapper's attributes), seeding
through numpy's global generator checked against the reference's recorded observations and
against the same draws made with numpy itself, `sample_tasks` against `composuite tasks` for every
experiment type and element, bad input failing as the reference fails, and a script written for
CompoSuite that runs after changing only its import."""

from __future__ import annotations

import gzip
import json
import random
import subprocess
import sys
import textwrap

import numpy as np
import pytest

from node_suite import REPO, float_bits

from composuite_ros import CompoSuiteNativeEnv, compat

ROBOTS = ["IIWA", "Jaco", "Kinova3", "Panda"]
OBJECTS = ["Box", "Dumbbell", "Plate", "Hollowbox"]
OBSTACLES = ["None", "GoalWall", "ObjectDoor", "ObjectWall"]
OBJECTIVES = ["PickPlace", "Push", "Shelf", "Trashcan"]
ELEMENTS = ROBOTS + OBJECTS + OBSTACLES + OBJECTIVES
# One task per objective; together every robot, object and obstacle once.
TASKS = [("IIWA", "Box", "None", "PickPlace"), ("Jaco", "Plate", "ObjectWall", "Shelf"),
         ("Kinova3", "Hollowbox", "ObjectDoor", "Trashcan"),
         ("Panda", "Dumbbell", "GoalWall", "Push")]


def numpy_state() -> tuple:
    """numpy's global generator state as comparable plain values."""
    name, key, pos, has_gauss, cached = np.random.get_state()
    return name, key.tolist(), int(pos), int(has_gauss), float(cached)


# ---- the reference's draws, made with numpy itself (docs/src/reference-facts.md §2.2, §7.3) ----

RADIUS = {"Box": 0.02, "Dumbbell": 0.045, "Plate": 0.06, "Hollowbox": 0.038}
# An obstacle's body xy and the radius the placement keeps the object clear of.
OBSTACLE_AT = {"ObjectWall": ((0.1 - 0.2 / 2.2, -0.26), 0.1),
               "ObjectDoor": ((0.1 - 0.2 / 2.2, -0.26), 0.07),
               "GoalWall": ((0.1, -0.01), 0.08)}


def reference_reset_draws(obj: str, obstacle: str) -> tuple[float, float]:
    """One reset's draws from `np.random`, in the reference's order; returns the object's xy."""
    np.random.randn(7)  # the arm's initialisation noise, multiplied by 0 but drawn
    if obstacle != "None":
        np.random.uniform(0.0, 0.0)  # the obstacle's x and y over an empty range
        np.random.uniform(0.0, 0.0)
    r = RADIUS[obj]
    x_low = 0.0 if obstacle in ("ObjectWall", "ObjectDoor") else -0.1  # beyond a wall or door
    for _ in range(5000):
        x = np.random.uniform(x_low + r, 0.1 - r) + 0.1
        y = np.random.uniform(-0.125 + r, 0.125 - r) - 0.26
        if obstacle == "None":
            break
        (ox, oy), clear = OBSTACLE_AT[obstacle]
        if np.hypot(x - ox, y - oy) > clear + r:
            break
    np.random.uniform(0.0, 0.0)  # the goal marker's x and y
    np.random.uniform(0.0, 0.0)
    return x, y


# ---- the documented usage ------------------------------------------------------------------------

def test_readme_usage_single_task_without_ids():
    """The reference README's call: a Gym env for single-task training, 77 values."""
    env = compat.make("IIWA", "Box", "None", "PickPlace", use_task_id_obs=False)
    obs = env.reset()
    assert isinstance(obs, np.ndarray) and obs.dtype == np.float64 and obs.shape == (77,)
    obs, reward, done, info = env.step(np.zeros(8))
    assert obs.shape == (77,) and isinstance(reward, float) and done is False
    assert info == {"Success": 0}


def test_wrapper_attributes():
    env = compat.make("Kinova3", "Hollowbox", "ObjectDoor", "Trashcan", use_task_id_obs=True)
    assert env.name == "Kinova3_TrashcanSubtask"
    assert env.keys == ["object-state", "obstacle-state", "goal-state", "object_id", "robot_id",
                        "obstacle_id", "subtask_id", "robot0_proprio-state"]
    assert env.modality_dims == {"object-state": (14,), "obstacle-state": (14,),
                                 "goal-state": (17,), "object_id": (4,), "robot_id": (4,),
                                 "obstacle_id": (4,), "subtask_id": (4,),
                                 "robot0_proprio-state": (32,)}
    assert env.obs_dim == 93
    starts = {"object-state": 0, "obstacle-state": 14, "goal-state": 28, "object_id": 45,
              "robot_id": 49, "obstacle_id": 53, "subtask_id": 57, "robot0_proprio-state": 61}
    for key, start in starts.items():
        size = env.modality_dims[key][0]
        assert env.observation_positions[key].tolist() == list(range(start, start + size)), key
    obs = env.reset()
    # The one-hots (§5: object Box Dumbbell Plate Hollowbox; robot IIWA Jaco Panda Kinova3;
    # obstacle None ObjectWall ObjectDoor GoalWall; objective PickPlace Push Shelf Trashcan).
    ids = {k: int(np.argmax(obs[env.observation_positions[k]]))
           for k in ("object_id", "robot_id", "obstacle_id", "subtask_id")}
    assert ids == {"object_id": 3, "robot_id": 3, "obstacle_id": 2, "subtask_id": 3}
    assert env.observation_space.shape == (93,) and env.observation_space.dtype == np.float32
    assert np.all(np.isinf(env.observation_space.low)) and np.all(env.observation_space.high > 0)
    assert env.action_space.shape == (8,)
    assert env.action_space.low.tolist() == [-1.0] * 8
    assert env.action_space.high.tolist() == [1.0] * 8
    low, high = env.action_spec
    assert low.tolist() == [-1.0] * 8 and high.tolist() == [1.0] * 8 and env.action_dim == 8
    assert env.reward_range == (0, 1.0)
    assert env.metadata is None and env.spec is None and env.unwrapped is env
    settings = (env.horizon, env.ignore_done, env.reward_shaping, env.use_task_id_obs)
    assert settings == (500, True, True, True)
    scaled = compat.make("IIWA", "Box", None, "Shelf", reward_scale=2.5)
    assert scaled.name == "IIWA_ShelfSubtask" and scaled.reward_range == (0, 2.5)
    assert scaled.obs_dim == 77 and "object_id" not in scaled.keys
    assert scaled.observation_positions["robot0_proprio-state"].tolist() == list(range(45, 77))
    with pytest.raises(AttributeError, match="no robosuite environment"):
        env.sim  # noqa: B018 - the reference forwarded this to robosuite


def test_loop_to_done_at_the_horizon_and_no_step_after():
    """ignore_done=False: done after env_horizon steps; then only reset() continues."""
    env = compat.make("Panda", "Plate", "GoalWall", "Shelf", env_horizon=25, ignore_done=False)
    np.random.seed(3)
    env.reset()
    done, steps = False, 0
    rng = np.random.default_rng(0)
    while not done:
        obs, reward, done, info = env.step(rng.uniform(-1, 1, 8))
        steps += 1
        assert set(info) == {"Success"} and info["Success"] == (1 if reward == 1 else 0)
    assert steps == 25 and env.timestep == 25 and env.done
    with pytest.raises(ValueError, match="^executing action in terminated episode$"):
        env.step(np.zeros(8))
    env.reset()
    assert env.timestep == 0 and not env.done
    env.step(np.zeros(8))


def test_ignore_done_never_ends_for_length():
    """The default: the caller cuts the episode (the reference's training loop at 500)."""
    env = compat.make("IIWA", "Box", "None", "PickPlace")
    np.random.seed(0)
    env.reset()
    for _ in range(510):
        _, _, done, _ = env.step(np.zeros(8))
        assert not done
    assert env.timestep == 510


def test_same_as_the_native_env_bit_for_bit():
    """`np.random.seed(s); env.reset()` is the native env's `reset(seed=s)`: the same episode,
    observations and rewards bit for bit; `Success` is the reward being 1; actions beyond
    [-1, 1] are clipped the same way."""
    rng = np.random.default_rng(7)
    for robot, obj, obstacle, objective in TASKS:
        env = compat.make(robot, obj, obstacle, objective, use_task_id_obs=True)
        native = CompoSuiteNativeEnv("/".join((robot, obj, obstacle, objective)))
        for seed in (0, 11):
            np.random.seed(seed)
            ours = env.reset()
            theirs, _ = native.reset(seed=seed)
            assert float_bits(ours) == float_bits(theirs), (robot, obj, obstacle, objective, seed)
            for t in range(30):
                action = rng.uniform(-1.5, 1.5, 8)
                ours, reward, done, info = env.step(action)
                theirs, native_reward, terminated, truncated, native_info = native.step(
                    np.clip(action, -1, 1))
                where = (robot, obj, obstacle, objective, seed, t)
                assert float_bits(ours) == float_bits(theirs), where
                assert float_bits([reward]) == float_bits([native_reward]), where
                assert done == terminated and not truncated, where
                assert info == {"Success": int(native_info["success"])}, where


# ---- seeding as the reference: numpy's global generator ------------------------------------------

STEP0 = REPO / "tests" / "reference" / "data" / "step0.json.gz"


def test_step0_observations_equal_the_references():
    """`np.random.seed(s); env.reset()` against the reference's own recorded step-0
    observations (CompoSuite 1fa36f6 on robosuite 1.4.0; seeded the same way). The record keeps
    7 decimals; the bound is the Rust fidelity test's (nodes/core/tests/reference_fidelity.rs)."""
    data = json.loads(gzip.decompress(STEP0.read_bytes()))
    records = {tuple(r["reference"].values()): r["seeds"] for r in data["tasks"]}
    for task in TASKS:
        env = compat.make(*task, use_task_id_obs=True)
        for case in records[task]:
            np.random.seed(case["seed"])
            obs = env.reset()
            recorded = np.array(case["obs"])
            worst = int(np.argmax(np.abs(obs - recorded)))
            assert abs(obs[worst] - recorded[worst]) <= 1e-4, (task, case["seed"], worst)
            # The object's start, which the seed decides, to the record's 7 decimals.
            assert np.abs(obs[:3] - recorded[:3]).max() <= 1e-7, (task, case["seed"])


@pytest.mark.parametrize("obstacle", OBSTACLES)
def test_reset_draws_as_numpy_itself(obstacle):
    """After `np.random.seed(s); env.reset()`, numpy's state is where the same draws made with
    numpy leave it, and the object starts where those draws put it — for every object and
    obstacle, and through consecutive resets (where a cached normal carries over)."""
    for obj in OBJECTS:
        env = compat.make("Jaco", obj, obstacle, "Push")
        for seed in (0, 1, 2**32 - 1):
            np.random.seed(seed)
            starts = [env.reset()[:2] for _ in range(3)]
            after = numpy_state()
            np.random.seed(seed)
            expected = [reference_reset_draws(obj, obstacle) for _ in range(3)]
            assert numpy_state() == after, (obj, obstacle, seed)
            # The physics keeps positions in single precision: the start is the draw rounded so.
            rounded = np.array(expected, dtype=np.float32).astype(np.float64)
            assert float_bits(np.ravel(starts)) == float_bits(rounded.ravel()), \
                (obj, obstacle, seed)


def test_make_takes_four_resets_of_draws():
    """The reference's construction resets four times; so does `make`, and its first episode
    is the fourth's."""
    for robot, obj, obstacle, objective in TASKS:
        np.random.seed(5)
        env = compat.make(robot, obj, obstacle, objective)
        after_make = numpy_state()
        first = env.step(np.zeros(8))[0]
        np.random.seed(5)
        for _ in range(4):
            reference_reset_draws(obj, obstacle)
        assert numpy_state() == after_make, (robot, obj, obstacle, objective)
        # The same start from a reset after three resets' worth of draws.
        other = compat.make(robot, obj, obstacle, objective)
        np.random.seed(5)
        for _ in range(3):
            reference_reset_draws(obj, obstacle)
        other.reset()
        assert float_bits(other.step(np.zeros(8))[0]) == float_bits(first)


def test_seed_is_numpys_global_seed():
    env = compat.make()
    env.seed(9)
    state = numpy_state()
    np.random.seed(9)
    assert numpy_state() == state
    env.seed("not a seed")  # the reference's wrapper ignores what numpy refuses
    assert numpy_state() == state
    env.seed(None)
    assert numpy_state() == state


# ---- Push's early end, with a scripted grasp -----------------------------------------------------

def plan_actions(plan: dict, hold: int, observation: np.ndarray):
    """The committed grasp plan's closed loop (tests/reference/data/grasp_plans.json.gz): each
    target held `hold` steps, the joints driven towards it from the observed angles (the
    93-value observation: joint cosines at 61..67, sines at 68..74)."""
    for targets, gripper in zip(plan["targets"], plan["gripper"]):
        for _ in range(hold):
            q = np.arctan2(observation[68:75], observation[61:68])
            error = np.mod(np.asarray(targets) - q + np.pi, 2 * np.pi) - np.pi
            observation = yield np.append(np.clip(error / 0.05, -1, 1), gripper)


def play(env, plan: dict, hold: int, seed: int) -> tuple[int | None, int | None]:
    """(first step with Success, step that ended the episode) of the plan played in `env`."""
    np.random.seed(seed)
    observation = env.reset()
    actions = plan_actions(plan, hold, observation)
    action = next(actions)
    first_success = None
    for step in range(1, len(plan["targets"]) * hold + 1):
        observation, _, done, info = env.step(action)
        if info["Success"] and first_success is None:
            first_success = step
        if done:
            return first_success, step
        try:
            action = actions.send(observation)
        except StopIteration:
            break
    return first_success, None


def test_a_scripted_pick_and_place_succeeds_and_push_ends_when_lifted():
    """A scripted expert's closed loop through compat, as a user's agent would run: the pick and
    place succeeds (the reference's run of the same plan first succeeds at step 738; the bound
    is reference_fidelity.rs's GRASP_SUCCESS_STEPS, measured here: 733); the same
    grasp and lift on Push ends the episode whatever ignore_done says, at the step the native env
    terminates, and a further step is refused."""
    plans = json.loads(gzip.decompress((STEP0.parent / "grasp_plans.json.gz").read_bytes()))
    hold = plans["meta"]["hold"]
    plan = next(e for e in plans["episodes"]
                if e["name"] == "IIWA/box/no_obstacle/pick_place" and e["seed"] == 0)
    pick_place = compat.make("IIWA", "Box", None, "PickPlace", use_task_id_obs=True)
    first_success, ended = play(pick_place, plan, hold, 0)
    assert first_success is not None and abs(first_success - 738) <= 60 and ended is None

    native = CompoSuiteNativeEnv("IIWA/box/no_obstacle/push", horizon=10_000)
    observation, _ = native.reset(seed=0)
    actions = plan_actions(plan, hold, observation)
    action, terminated_at = next(actions), None
    for step in range(1, 2001):
        observation, _, terminated, _, _ = native.step(action)
        if terminated:
            terminated_at = step
            break
        action = actions.send(observation)
    assert terminated_at is not None, "the plan lifts the box"
    for ignore_done in (True, False):
        env = compat.make("IIWA", "Box", "None", "Push", ignore_done=ignore_done,
                          use_task_id_obs=True)
        _, ended = play(env, plan, hold, 0)
        assert ended == terminated_at, ignore_done
        with pytest.raises(ValueError, match="executing action in terminated episode"):
            env.step(np.zeros(8))


# ---- bad input fails as the reference fails ------------------------------------------------------

@pytest.mark.parametrize("kwargs", [
    {"robot": "Sawyer"}, {"robot": "Gen3"}, {"robot": "iiwa"},
    {"obj": "box"}, {"obj": "hollow_box"}, {"obj": "Milk"},
    {"obstacle": "none"}, {"obstacle": "no_obstacle"}, {"obstacle": "Goalwall"},
    {"task": "pick_place"}, {"task": "Lift"}, {"task": "TrashCan"},
])
def test_misspelled_names_are_assertion_errors(kwargs):
    np.random.seed(1)
    before = numpy_state()
    with pytest.raises(AssertionError):
        compat.make(**kwargs)
    assert numpy_state() == before, "nothing was built, nothing drawn"


@pytest.mark.parametrize("kwargs, error, match", [
    ({"controller": "osc"}, NotImplementedError, "joint"),
    ({"controller": "osc_pose"}, NotImplementedError, "joint"),
    ({"controller": "OSC_POSITION"}, NotImplementedError, "joint"),
    ({"has_renderer": True}, NotImplementedError, "renderer"),
    ({"has_offscreen_renderer": True}, NotImplementedError, "renderer"),
    ({"use_camera_obs": True}, ValueError, "offscreen renderer"),
    ({"use_camera_obs": True, "has_offscreen_renderer": True}, NotImplementedError, "camera"),
    ({"horizon": 100}, TypeError, "multiple values"),
    ({"controller_configs": {}}, TypeError, "multiple values"),
    ({"no_such_setting": 1}, TypeError, "use_task_id_obs"),
    ({"gripper_types": "PandaGripper"}, ValueError, "RethinkGripper"),
    ({"control_freq": 10}, NotImplementedError, "control_freq=20"),
    ({"initialization_noise": "default"}, NotImplementedError, "initialization_noise=None"),
    ({"use_object_obs": False}, NotImplementedError, "use_object_obs=True"),
    ({"bin2_pos": (0.1, 0.3, 0.8)}, NotImplementedError, "bin2_pos"),
    ({"reward_scale": float("nan")}, ValueError, "reward_scale"),
])
def test_unsupported_settings_fail_naming_what_is_supported(kwargs, error, match):
    with pytest.raises(error, match=match):
        compat.make(**kwargs)


def test_settings_that_change_nothing_are_accepted():
    env = compat.make("Jaco", "Box", "GoalWall", "Shelf", hard_reset=False,
                      camera_names="frontview", camera_heights=84, render_camera=None,
                      control_freq=20, mount_types="default", gripper_types="RethinkGripper",
                      initialization_noise=None, use_object_obs=True, bin1_pos=[0.1, -0.26, 0.8],
                      bin2_pos=(0.1, 0.18, 0.8), env_configuration="default", reward_scale=None)
    assert env.reward_range == (0, None)
    np.random.seed(0)
    env.reset()
    _, reward, _, _ = env.step(np.zeros(8))
    assert 0 <= reward < 1


def test_bad_actions():
    env = compat.make()
    with pytest.raises(AssertionError, match="expected 8, got 7"):
        env.step(np.zeros(7))
    with pytest.raises(AssertionError):
        env.step(np.zeros((1, 8)))  # one row of 8 has length 1, as robosuite counts it
    with pytest.raises(ValueError, match="non-finite"):
        env.step([0, 0, 0, np.nan, 0, 0, 0, 0])
    env.step([0.0] * 8)  # a list does as well as an array


def test_close_then_reset_builds_again():
    env = compat.make()
    env.close()
    with pytest.raises(RuntimeError, match="reset"):
        env.step(np.zeros(8))
    assert env.reset().shape == (77,)
    with compat.make() as scoped:
        scoped.step(np.zeros(8))
    with pytest.raises(NotImplementedError, match="renderer"):
        env.render()


def test_compute_reward_is_the_last_steps():
    env = compat.make()
    env.reset()
    with pytest.raises(NotImplementedError):
        env.compute_reward(None, None, None)
    _, reward, _, _ = env.step(np.zeros(8))
    assert env.compute_reward(None, None, {}) == reward


# ---- sample_tasks --------------------------------------------------------------------------------

# Equality with `composuite tasks` (the Rust implementation) for every experiment type, element,
# several seeds and sizes: test_splits_reference.py, which uses this module's sample_tasks.


@pytest.mark.parametrize("element", ELEMENTS)
def test_sample_tasks_split_shapes(element):
    train, test = compat.sample_tasks("holdout", 56, holdout_elem=element, shuffling_seed=3)
    assert len(train) == 56 and len(test) == 63
    assert [element in t for t in train] == [False] * 55 + [True]
    assert all(element in t for t in test)
    train, test = compat.sample_tasks("smallscale", 32, smallscale_elem=element, shuffling_seed=3)
    assert len(train) == 32 and len(test) == 32 and all(element in t for t in train + test)


def test_sample_tasks_unshuffled_is_the_reference_order():
    # The order the reference's single-task `--task-id k` indexes.
    _, tasks = compat.sample_tasks(num_train=0, no_shuffle=True)
    assert tasks[5] == ("IIWA", "Box", "GoalWall", "Push") and len(tasks) == 256


def test_sample_tasks_leave_pythons_random_alone():
    random.seed(123)
    state = random.getstate()
    compat.sample_tasks(num_train=10, shuffling_seed=7)
    assert random.getstate() == state
    # Unseeded, the shuffle continues the caller's stream, which is then put back as it was.
    first = compat.sample_tasks(num_train=10)
    assert random.getstate() == state
    assert compat.sample_tasks(num_train=10) == first


def test_sample_tasks_tuples_make_environments():
    train, _ = compat.sample_tasks("smallscale", 2, smallscale_elem="None", shuffling_seed=0)
    for task in train:
        assert task[2] == "None"
        assert compat.make(*task).reset().shape == (77,)


def test_sample_tasks_fail_and_quirk_as_the_reference():
    bounds = {"default": (-1, 257), "smallscale": (-1, 65), "holdout": (0, 194)}
    for experiment, bad in bounds.items():
        for num_train in bad:
            with pytest.raises(AssertionError):
                compat.sample_tasks(experiment, num_train, smallscale_elem="IIWA",
                                    holdout_elem="IIWA")
    with pytest.raises(NotImplementedError):
        compat.sample_tasks("fewshot")
    for unknown in ("Sawyer", "iiwa", "no_obstacle"):
        with pytest.raises(NotImplementedError):
            compat.sample_tasks("smallscale", 1, smallscale_elem=unknown)
    with pytest.warns(UserWarning):
        compat.sample_tasks("default", 1, holdout_elem="IIWA", shuffling_seed=0)
    # Smallscale without an element: None is in the reference's obstacle list, so the split
    # keeps the obstacle None (as a None, which make() accepts).
    train, test = compat.sample_tasks("smallscale", 4, shuffling_seed=0)
    assert len(train) + len(test) == 64 and {t[2] for t in train + test} == {None}
    compat.make(*train[0])
    # Holdout without an element: nothing has it, so there is no test set.
    train, test = compat.sample_tasks("holdout", 10, shuffling_seed=0)
    assert len(train) == 9 and test == []


# ---- a script written for CompoSuite -------------------------------------------------------------

SCRIPT = textwrap.dedent("""\
    import json

    import numpy as np
    import composuite

    np.random.seed(42)
    _, all_tasks = composuite.sample_tasks(experiment_type="default", num_train=0, no_shuffle=True)
    robot, obj, obstacle, task = all_tasks[5]
    train_tasks, test_tasks = composuite.sample_tasks(
        experiment_type="smallscale", num_train=4, smallscale_elem="IIWA", holdout_elem="IIWA",
        shuffling_seed=42, no_shuffle=False)

    def env_fn():
        return composuite.make(robot, obj, obstacle, task, "joint", 500, use_task_id_obs=True)

    env = env_fn()
    env.seed(42)
    obs_dim = env.observation_space.shape
    act_dim = env.action_space.shape
    max_ep_len = 40
    o, ep_ret, ep_len = env.reset(), 0, 0
    episodes = []
    for t in range(100):
        a = np.random.uniform(env.action_space.low, env.action_space.high)
        o, r, d, info = env.step(a)
        ep_ret += r
        ep_len += 1
        if d or ep_len == max_ep_len:
            episodes.append([ep_len, round(float(ep_ret), 9), info["Success"]])
            o, ep_ret, ep_len = env.reset(), 0, 0
    modules = {name: int(np.argmax(o[env.observation_positions[name]]))
               for name in ("obstacle_id", "object_id", "subtask_id", "robot_id")}
    inputs = {name: len(env.observation_positions[name])
              for name in ("obstacle-state", "object-state", "goal-state", "robot0_proprio-state")}
    print(json.dumps({"task": [robot, obj, obstacle, task], "train": train_tasks, "name": env.name,
                      "obs_dim": obs_dim, "act_dim": act_dim, "episodes": episodes,
                      "modules": modules, "inputs": inputs, "last": o.tolist()}))
    """)


def test_a_composuite_script_runs_with_only_its_import_changed():
    """A script in the reference's style (its example training script's use of sample_tasks,
    make, the wrapper's spaces and observation positions, the old Gym loop) runs unchanged but
    for its import, and seeding makes it reproducible."""
    assert SCRIPT.count("import composuite\n") == 1
    script = SCRIPT.replace("import composuite\n",
                            "from composuite_ros import compat as composuite\n")
    outputs = [subprocess.run([sys.executable, "-c", script], capture_output=True, text=True,
                              check=False, timeout=300) for _ in range(2)]
    for result in outputs:
        assert result.returncode == 0, result.stderr
    assert outputs[0].stdout == outputs[1].stdout
    report = json.loads(outputs[0].stdout)
    assert report["task"] == ["IIWA", "Box", "GoalWall", "Push"]
    assert report["name"] == "IIWA_PushSubtask"
    assert report["obs_dim"] == [93] and report["act_dim"] == [8]
    assert [e[0] for e in report["episodes"]] == [40, 40]
    assert report["modules"] == {"obstacle_id": 3, "object_id": 0, "subtask_id": 1, "robot_id": 0}
    assert report["inputs"] == {"obstacle-state": 14, "object-state": 14, "goal-state": 17,
                                "robot0_proprio-state": 32}
    assert len(report["train"]) == 4 and all(t[0] == "IIWA" for t in report["train"])
    assert report["train"] == [list(t) for t in compat.sample_tasks(
        "smallscale", 4, smallscale_elem="IIWA", shuffling_seed=42)[0]]
