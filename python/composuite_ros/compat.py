"""The reference benchmark's own API — `composuite.make` and `composuite.sample_tasks` — on the
in-process simulation core, so a script written for CompoSuite (Lifelong-ML/CompoSuite, commit
1fa36f6, on robosuite 1.4.0) runs after changing only its import:

    from composuite_ros import compat as composuite

    train, test = composuite.sample_tasks(experiment_type="smallscale", smallscale_elem="IIWA",
                                          num_train=32, shuffling_seed=42)
    env = composuite.make(*train[0], use_task_id_obs=True)
    np.random.seed(0)
    obs = env.reset()                               # flat numpy array, 93 values (77 without ids)
    done = False
    while not done and env.timestep < 500:
        obs, reward, done, info = env.step(env.action_space.sample())   # info == {"Success": 0|1}

What is the same as the reference (docs/src/reference-facts.md §1, §5, §7):

- `make`'s signature, defaults and spellings (robots IIWA, Jaco, Kinova3, Panda; objects Box,
  Dumbbell, Plate, Hollowbox; obstacles None or "None", GoalWall, ObjectDoor, ObjectWall;
  objectives PickPlace, Push, Shelf, Trashcan — exactly these, as the reference asserts: an
  `AssertionError` for anything else, `NotImplementedError` for an unknown controller).
- The returned object behaves as the reference's Gym wrapper (robosuite 1.4's `GymWrapper` as
  CompoSuite extends it): the old Gym API `reset() -> obs`, `step(a) -> (obs, reward, done,
  info)`, `seed(s)` (only `np.random.seed(s)`), `name`, `keys`, `obs_dim`, `modality_dims`,
  `observation_positions`, `reward_range`, `observation_space`, `action_space`, `metadata`,
  `spec`, `compute_reward`, `close`.
- Seeding: the object's start is drawn from numpy's *global* legacy generator exactly as the
  reference draws it (§7.3), so `np.random.seed(s); env.reset()` gives the reference's episode
  for seed s and leaves `np.random` in the reference's state afterwards. `make` takes the same
  draws as the reference's construction (four resets' worth): seed after `make`, as with the
  reference, to choose the first episode.
- Episode end: with `ignore_done=True` (the default) the environment never ends an episode for
  length — the caller cuts at its horizon; with `ignore_done=False` `done` turns True at
  `env_horizon` steps. Push ends early when the object is lifted more than 10 cm, whatever
  `ignore_done` says. Stepping an ended episode raises
  `ValueError("executing action in terminated episode")`; only `reset()` continues.
- `info` is `{"Success": 1}` exactly when the step's (scaled) reward equals 1, else
  `{"Success": 0}`; out-of-range actions are clipped to [-1, 1]; a wrong action length is an
  `AssertionError`.
- `sample_tasks` is the reference's algorithm on CPython's own `random` (state saved and
  restored), so its splits are the reference's for every seed, quirks included (§7.2).

What differs (each fails loudly, naming what is supported):

- Only `controller="joint"` (the benchmark's; `"osc"`/`"osc_pose"` raise
  `NotImplementedError`), no renderers and no camera observations (`has_renderer`,
  `has_offscreen_renderer` True raise `NotImplementedError`; `use_camera_obs=True` without an
  off-screen renderer raises the reference's own `ValueError`).
- Of the extra keyword arguments the reference passes to robosuite, `use_task_id_obs` (default
  False, as the reference's) and `reward_scale` (a number or None) take effect; the rendering
  and camera settings and `hard_reset` are accepted and change nothing here, as they change
  nothing without renderers in the reference; `env_configuration`, `mount_types`,
  `gripper_types`, `initialization_noise`, `use_object_obs`, `control_freq`, `bin1_pos` and
  `bin2_pos` are accepted at their reference defaults only (`NotImplementedError` otherwise; a
  gripper other than RethinkGripper is the reference's own `ValueError`). Any other keyword is a
  `TypeError`, as in the reference.
- The spaces are Gymnasium's `Box` (the reference built gym's). As in the reference they are
  float32 (gym's default) while observations are float64 numpy arrays.
- There is no robosuite environment underneath: the wrapper's `env` (robosuite's `MujocoEnv`,
  its `sim`, `robots`, ...) does not exist. The wrapper itself answers the plain settings
  scripts read from it (`horizon`, `ignore_done`, `reward_scale`, `reward_shaping`,
  `use_task_id_obs`, `timestep`, `done`, `action_spec`, `action_dim`, `control_freq`).
- Non-finite actions raise `ValueError` (the reference would feed NaN to the physics);
  `render()` raises `NotImplementedError`. `compute_reward` returns the last step's reward: the
  reference recomputes it from the unchanged state without the action, which gives the same
  number (except where Trashcan's drop stage needs the action: there the reference fails), and
  before the first step of an episode, where there is no step's reward, it raises
  `NotImplementedError`.
"""

from __future__ import annotations

import itertools
import random
import warnings
from typing import Any

import numpy as np
from gymnasium import spaces

from . import _native

AVAILABLE_ROBOTS = ["IIWA", "Jaco", "Kinova3", "Panda"]
AVAILABLE_OBSTACLES = [None, "None", "GoalWall", "ObjectDoor", "ObjectWall"]
AVAILABLE_OBJECTS = ["Box", "Dumbbell", "Plate", "Hollowbox"]
AVAILABLE_TASKS = ["PickPlace", "Push", "Shelf", "Trashcan"]
AVAILABLE_CONTROLLERS = ["joint"]

# robosuite's environment class per objective: the second half of the wrapper's `name`.
_ENV_CLASS = {"PickPlace": "PickPlaceSubtask", "Push": "PushSubtask", "Shelf": "ShelfSubtask",
              "Trashcan": "TrashcanSubtask"}
# The robosuite controllers the reference's `make` knows, by its own name for them.
_REFERENCE_CONTROLLERS = {"osc": "OSC_POSITION", "joint": "JOINT_POSITION",
                          "osc_pose": "OSC_POSE"}

# Keywords the reference's `make` itself hands robosuite: one in **kwargs too is given twice.
_GIVEN_BY_MAKE = ("env_name", "robots", "obstacle", "object_type", "controller_configs",
                  "has_renderer", "has_offscreen_renderer", "reward_shaping", "ignore_done",
                  "use_camera_obs", "horizon")
# Keywords that only matter to a renderer, which neither side has here.
_RENDER_ONLY = ("render_camera", "render_collision_mesh", "render_visual_mesh",
                "render_gpu_device_id", "camera_names", "camera_heights", "camera_widths",
                "camera_depths")
_BIN1_DEFAULT = (0.1, -0.26, 0.8)
# The task classes' own bin-2 defaults (Shelf's differs).
_BIN2_DEFAULT = {"PickPlace": (0.1, 0.13, 0.8), "Push": (0.1, 0.13, 0.8),
                 "Shelf": (0.1, 0.18, 0.8), "Trashcan": (0.1, 0.13, 0.8)}

# The flat observation's keys in the wrapper's order (§5) and their sizes.
_STATE_KEYS = (("object-state", 14), ("obstacle-state", 14), ("goal-state", 17))
_ID_KEYS = (("object_id", 4), ("robot_id", 4), ("obstacle_id", 4), ("subtask_id", 4))
_PROPRIO_KEY = ("robot0_proprio-state", 32)

ACTION_DIM = 8
# The Batch's horizon when nothing may end an episode for length (`ignore_done=True`): its
# step counter is 32-bit, so this is as far as "never" goes — 6.8 years of control at 20 Hz.
_NO_HORIZON = 2**32 - 1


def make(robot="IIWA", obj="Box", obstacle=None, task="PickPlace", controller="joint",
         env_horizon=500, has_renderer=False, has_offscreen_renderer=False, reward_shaping=True,
         ignore_done=True, use_camera_obs=False, **kwargs) -> GymWrapper:
    """One CompoSuite task as the reference's Gym-style environment (see the module docs).

    Args:
        robot: "IIWA", "Jaco", "Kinova3" or "Panda".
        obj: "Box", "Dumbbell", "Plate" or "Hollowbox".
        obstacle: None or "None" (no obstacle), "GoalWall", "ObjectDoor" or "ObjectWall".
        task: the objective, "PickPlace", "Push", "Shelf" or "Trashcan".
        controller: "joint" (robosuite's JOINT_POSITION: 7 normalised joint deltas and the
            gripper), the only one here.
        env_horizon: the episode length at which `done` turns True when `ignore_done` is False.
        has_renderer, has_offscreen_renderer, use_camera_obs: False (no rendering here).
        reward_shaping: staged rewards (True) or 1 on success and 0 otherwise.
        ignore_done: True: the environment never ends an episode for length (Push still ends
            when the object is lifted).
        **kwargs: `use_task_id_obs` (False: 77 values; True: 93, with the task's one-hots),
            `reward_scale` (1.0; None for unscaled), and the settings listed in the module docs.

    Raises:
        AssertionError: a robot, object, obstacle or objective not spelled as the reference
            spells it (e.g. "Gen3", "box", "no_obstacle").
        NotImplementedError: a controller other than "joint", a renderer, or a setting this
            port does not model (the message names what is supported).
        ValueError: `use_camera_obs=True` without an off-screen renderer, a gripper other than
            RethinkGripper (both as the reference).
        TypeError: a keyword the reference does not know, or one `make` already gives.

    Building takes four resets' worth of draws from `np.random`, as the reference's does.
    """
    # The reference's checks, in its order.
    assert robot in AVAILABLE_ROBOTS
    assert obstacle in AVAILABLE_OBSTACLES
    assert obj in AVAILABLE_OBJECTS
    assert task in AVAILABLE_TASKS
    if obstacle == "None":
        obstacle = None
    if controller not in _REFERENCE_CONTROLLERS:
        raise NotImplementedError(
            f"controller {controller!r} is unknown (the reference knows "
            f"{', '.join(map(repr, _REFERENCE_CONTROLLERS))}; this port supports 'joint' only)")
    if controller != "joint":
        raise NotImplementedError(
            f"controller {controller!r} (robosuite's {_REFERENCE_CONTROLLERS[controller]}) is not "
            "supported: composuite_ros.compat has controller='joint' only (JOINT_POSITION, the "
            "benchmark's)")
    settings = _settings(task, kwargs)
    if use_camera_obs and not has_offscreen_renderer:
        # robosuite's own refusal and message (scripts may match on it).
        raise ValueError("Error: Camera observations require an offscreen renderer!")
    for name, value in (("has_renderer", has_renderer),
                        ("has_offscreen_renderer", has_offscreen_renderer),
                        ("use_camera_obs", use_camera_obs)):
        if value:
            raise NotImplementedError(
                f"{name}=True is not supported: composuite_ros.compat has no renderer and no "
                "camera observations (has_renderer, has_offscreen_renderer and use_camera_obs "
                "must be False)")
    return GymWrapper(robot, obj, obstacle, task, env_horizon=env_horizon,
                      reward_shaping=bool(reward_shaping), ignore_done=ignore_done, **settings)


def _settings(task: str, kwargs: dict[str, Any]) -> dict[str, Any]:
    """The extra keywords the reference passes on to robosuite, checked: what takes effect
    here, as keyword arguments for `GymWrapper`."""
    for name in kwargs:
        if name in _GIVEN_BY_MAKE:
            raise TypeError(f"make() got multiple values for keyword argument {name!r}")
    kwargs = dict(kwargs)
    settings = {"use_task_id_obs": bool(kwargs.pop("use_task_id_obs", False))}
    scale = kwargs.pop("reward_scale", 1.0)
    if scale is not None and not np.isfinite(float(scale)):
        raise ValueError(f"reward_scale is {scale}; it must be a finite number or None")
    settings["reward_scale"] = scale
    for name in (*_RENDER_ONLY, "hard_reset"):
        kwargs.pop(name, None)
    gripper = kwargs.pop("gripper_types", "RethinkGripper")
    if gripper != "RethinkGripper":
        # The reference refuses too, so that every task's observation has the same layout.
        raise ValueError(f"gripper_types={gripper!r}: only 'RethinkGripper' can be used (every "
                         "task of the benchmark has the same gripper)")
    fixed = {"env_configuration": "default", "mount_types": "default",
             "initialization_noise": None, "use_object_obs": True, "control_freq": 20,
             "bin1_pos": _BIN1_DEFAULT, "bin2_pos": _BIN2_DEFAULT[task]}
    for name, default in fixed.items():
        if name not in kwargs:
            continue
        value = kwargs.pop(name)
        same = (value is None) == (default is None) and (
            default is None or np.array_equal(np.asarray(value), np.asarray(default)))
        if not same:
            raise NotImplementedError(
                f"{name}={value!r} is not supported: composuite_ros.compat models the "
                f"benchmark's {name}={default!r} only")
    if kwargs:
        supported = ["use_task_id_obs", "reward_scale", *fixed, "gripper_types", "hard_reset",
                     *_RENDER_ONLY]
        raise TypeError(f"make() got unexpected keyword argument(s) "
                        f"{', '.join(map(repr, sorted(kwargs)))}; the keywords it passes on are "
                        f"{', '.join(supported)}")
    return settings


class GymWrapper:
    """One task in-process with the reference's Gym-wrapper interface (old Gym API). Made by
    `make`; see the module docs for what it does and does not share with the reference.

    Attributes:
        name: "<robot>_<Objective>Subtask", e.g. "IIWA_PickPlaceSubtask".
        keys: the observation's parts in order ("object-state", ..., "robot0_proprio-state").
        modality_dims: each key's shape, e.g. {"object-state": (14,), ...}.
        observation_positions: each key's indices into the flat observation (numpy arrays).
        obs_dim: the flat observation's size (93 with the task one-hots, 77 without).
        observation_space, action_space: Gymnasium Boxes (unbounded; [-1, 1]^8), float32.
        reward_range: (0, reward_scale).
        timestep: steps taken in this episode; done: whether it has ended.
    """

    metadata = None
    spec = None

    def __init__(self, robot: str, obj: str, obstacle: str | None, task: str, *,
                 env_horizon=500, reward_shaping: bool = True, ignore_done=True,
                 use_task_id_obs: bool = False, reward_scale: float | None = 1.0):
        self.robot, self.obj, self.obstacle, self.task = robot, obj, obstacle, task
        self.horizon = env_horizon
        self.ignore_done = ignore_done
        self.reward_shaping = reward_shaping
        self.reward_scale = reward_scale
        self.use_task_id_obs = use_task_id_obs
        self.control_freq = 20
        self.name = f"{robot}_{_ENV_CLASS[task]}"
        self.reward_range = (0, reward_scale)
        keys = [*_STATE_KEYS, *(_ID_KEYS if use_task_id_obs else ()), _PROPRIO_KEY]
        self.keys = [key for key, _ in keys]
        self.modality_dims = {key: (size,) for key, size in keys}
        self.observation_positions = {}
        start = 0
        for key, size in keys:
            self.observation_positions[key] = np.arange(start, start + size)
            start += size
        self.obs_dim = start
        self.observation_space = spaces.Box(low=-np.inf, high=np.inf, shape=(self.obs_dim,),
                                            dtype=np.float32)
        low, high = self.action_spec
        self.action_space = spaces.Box(low=low.astype(np.float32), high=high.astype(np.float32),
                                       dtype=np.float32)
        self._batch = None
        self._open()
        if self._batch.observation_size != self.obs_dim:  # the layout above is the core's
            raise RuntimeError(f"the core's observation has {self._batch.observation_size} "
                               f"values; the reference's layout {self.obs_dim}")
        # The reference's construction resets four times (once building robosuite's
        # environment, once in `make`, twice in the wrappers' constructors): the same draws.
        for _ in range(4):
            self.reset()

    def _open(self) -> None:
        """The one-environment batch this wrapper steps (again after `close`)."""
        task = "/".join((self.robot, self.obj, self.obstacle or "None", self.task))
        scale = 1.0 if self.reward_scale is None else float(self.reward_scale)
        self._batch = _native.Batch([task], threads=1, horizon=_NO_HORIZON,
                                    use_task_id_obs=self.use_task_id_obs,
                                    reward_shaping=self.reward_shaping, reward_scale=scale)
        self._episode_open = False
        self.timestep = 0
        self.done = False
        self._last_reward: float | None = None

    # ---- the reference's Gym-wrapper API ---------------------------------------------------------

    def reset(self) -> np.ndarray:
        """Start an episode with the object where the reference puts it for numpy's global
        generator's current state; returns the flat observation. `np.random` advances as the
        reference's reset advances it."""
        if self._batch is None:
            self._open()
        _, key, pos, has_gauss, cached = np.random.get_state()
        key, pos, has_gauss, cached = self._batch.reset_numpy_state(
            0, np.asarray(key, dtype=np.uint32), int(pos), bool(has_gauss), float(cached))
        np.random.set_state(("MT19937", key, pos, int(has_gauss), cached))
        self._episode_open = True
        self.timestep = 0
        self.done = False
        self._last_reward = None
        return self._batch.observations[0].copy()

    def step(self, action) -> tuple[np.ndarray, float, bool, dict[str, int]]:
        """One control step (0.05 s): `action` is 7 joint deltas and the gripper, each in
        [-1, 1] (larger values are clipped). Returns `(obs, reward, done, info)` with
        `info = {"Success": 0 or 1}`."""
        if not self._episode_open:
            raise RuntimeError("this environment was closed: call reset() to start an episode")
        if self.done:
            raise ValueError("executing action in terminated episode")
        # The reference checks the length as robosuite does (an assertion).
        assert len(action) == ACTION_DIM, (
            f"environment got invalid action dimension -- expected {ACTION_DIM}, got {len(action)}")
        values = np.asarray(action, dtype=np.float64).reshape(-1)
        if values.shape != (ACTION_DIM,):
            raise ValueError(f"action has {values.size} values; expected {ACTION_DIM}")
        if not np.all(np.isfinite(values)):
            raise ValueError(f"action has non-finite values: {values.tolist()}")
        b = self._batch
        b.actions[0] = values
        b.modes[0] = _native.MODE_STEP
        b.run()
        self.timestep += 1
        reward = float(b.rewards[0])
        # Push's lift rule is the core's termination; the length limit is the wrapper's, as in
        # robosuite (done at `horizon` steps unless ignored).
        self.done = bool(b.terminated[0]) or (
            self.timestep >= self.horizon and not self.ignore_done)
        self._last_reward = reward
        return b.observations[0].copy(), reward, self.done, {"Success": 1 if reward == 1 else 0}

    def seed(self, seed=None) -> None:
        """`np.random.seed(seed)`, all the reference's wrapper does (it ignores a seed numpy
        refuses, and so does this)."""
        if seed is not None:
            try:
                np.random.seed(seed)
            except Exception:  # the reference swallows it too
                pass

    def compute_reward(self, achieved_goal=None, desired_goal=None, info=None) -> float:
        """The reward of the current state (the arguments are unused, as in the reference):
        the last step's reward."""
        if self._last_reward is None:
            raise NotImplementedError(
                "compute_reward() before the episode's first step: this port has the reward of "
                "each step, not of the state a reset starts in")
        return self._last_reward

    def render(self, *args, **kwargs):
        raise NotImplementedError("composuite_ros.compat has no renderer (make() with "
                                  "has_renderer=False only)")

    def close(self) -> None:
        """Release the simulation (a later `reset()` builds it again, as robosuite's does)."""
        self._batch = None
        self._episode_open = False

    # ---- robosuite environment settings scripts read through the wrapper ------------------------

    @property
    def action_spec(self) -> tuple[np.ndarray, np.ndarray]:
        """(low, high) of the action: -1 and 1 for each of the 8 values."""
        return -np.ones(ACTION_DIM), np.ones(ACTION_DIM)

    @property
    def action_dim(self) -> int:
        return ACTION_DIM

    @property
    def unwrapped(self) -> GymWrapper:
        return self

    def __enter__(self) -> GymWrapper:
        return self

    def __exit__(self, *exc) -> bool:
        self.close()
        return False

    def __getattr__(self, name: str):
        # Only reached for names this class lacks: the reference forwarded them to robosuite.
        raise AttributeError(
            f"{type(self).__name__!r} has no attribute {name!r}: composuite_ros.compat has no "
            "robosuite environment underneath (no env, sim, robots, ...); see the module docs "
            "for what the wrapper offers")

    def __repr__(self) -> str:
        return (f"<composuite_ros.compat.GymWrapper {self.name} "
                f"{'/'.join((self.robot, self.obj, self.obstacle or 'None', self.task))}>")


def sample_tasks(experiment_type="default", num_train=1, smallscale_elem=None, holdout_elem=None,
                 shuffling_seed=None, no_shuffle=False):
    """The reference's train/test split: `(train, test)`, lists of
    `(robot, object, obstacle, objective)` tuples in the reference's spellings (the obstacle
    "None" as a string), ready for `make(*task)`.

    Args:
        experiment_type: "default" (all 256 tasks), "smallscale" (the 64 tasks that have
            `smallscale_elem`) or "holdout" (one task with `holdout_elem` to train on, the rest
            of that element's tasks to test on).
        num_train: training tasks: 0..256 (default), 0..64 (smallscale), 1..193 (holdout).
        shuffling_seed: seeds Python's `random` for the shuffle; the caller's `random` state is
            restored afterwards. None: the shuffle continues the global stream (not
            reproducible), as in the reference.
        no_shuffle: keep the enumeration order (objective fastest, robot slowest).

    As in the reference: bounds fail with `AssertionError`; an unknown experiment type, or a
    smallscale element no axis has, with `NotImplementedError`; a default split given an
    element warns and ignores it; smallscale without an element keeps the obstacle None (the
    reference finds None in its obstacle list), and holdout without one has an empty test set.
    """
    if experiment_type == "smallscale":
        assert num_train >= 0 and num_train <= 64, \
            "smallscale: num_train must be between 0 and 64"
    elif experiment_type == "holdout":
        assert num_train >= 1 and num_train <= 193, \
            "holdout: num_train must be between 1 and 193"
    elif experiment_type == "default":
        assert num_train >= 0 and num_train <= 256, \
            "default: num_train must be between 0 and 256"
    else:
        raise NotImplementedError(f"experiment type {experiment_type!r} does not exist; "
                                  "choose default, smallscale or holdout")
    if experiment_type == "default" and (smallscale_elem is not None or holdout_elem is not None):
        warnings.warn("default experiment: the smallscale/holdout element is ignored",
                      stacklevel=2)

    robots, objects, objectives = AVAILABLE_ROBOTS, AVAILABLE_OBJECTS, AVAILABLE_TASKS
    obstacles = [o for o in AVAILABLE_OBSTACLES if o is not None]
    if experiment_type == "smallscale":
        # The reference's lookup order; None matches its obstacle list (a None obstacle).
        if smallscale_elem in AVAILABLE_ROBOTS:
            robots = [smallscale_elem]
        elif smallscale_elem in AVAILABLE_OBJECTS:
            objects = [smallscale_elem]
        elif smallscale_elem in AVAILABLE_OBSTACLES:
            obstacles = [smallscale_elem]
        elif smallscale_elem in AVAILABLE_TASKS:
            objectives = [smallscale_elem]
        else:
            elements = [*AVAILABLE_ROBOTS, *AVAILABLE_OBSTACLES[1:], *AVAILABLE_OBJECTS,
                        *AVAILABLE_TASKS]
            raise NotImplementedError(f"smallscale element {smallscale_elem!r} does not exist; "
                                      f"choose one of {', '.join(elements)}")

    configurations = list(itertools.product(robots, objects, obstacles, objectives))
    # CPython's own global `random`, as the reference uses it: the caller's stream untouched.
    state = random.getstate()
    if shuffling_seed is not None:
        random.seed(shuffling_seed)
    if not no_shuffle:
        random.shuffle(configurations)
    random.setstate(state)

    if experiment_type == "holdout":
        with_element = [c for c in configurations if holdout_elem in c]
        without = [c for c in configurations if holdout_elem not in c]
        # The one training task with the element comes last.
        return without[:num_train - 1] + with_element[:1], with_element[1:]
    return configurations[:num_train], configurations[num_train:]
