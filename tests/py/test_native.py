"""The in-process environments (`composuite_ros.native`, the compiled `composuite_ros._native`):
bit-identical to the Rust `Env` (env_replay) and to `CompoSuiteRosEnv` over the suite (real
rclpy on Fast DDS) — observations, rewards, flags and info, one task of each objective on every
robot, to the horizon and through a reset; the vector env with mixed tasks equal to the same
tasks alone, 1 thread equal to 2, next-step autoreset as Gymnasium 1.x defines it; Gymnasium's
checker; bad input; and the package without rclpy."""

from __future__ import annotations

import subprocess
import sys

import gymnasium
import numpy as np
import pytest
from gymnasium.utils.env_checker import check_env

from node_suite import REPO, env_replay_run, float_bits, launch_running

import composuite_ros
from composuite_ros import CompoSuiteNativeEnv, CompoSuiteNativeVectorEnv, EpisodeOverError

HORIZON = 30
# One task per objective, every robot once (the tests below that need only a few tasks).
TASKS = ["IIWA/box/no_obstacle/pick_place", "Jaco/dumbbell/object_wall/push",
         "Gen3/plate/goal_wall/trash_can", "Panda/hollow_box/object_door/shelf"]
ROBOTS = ("IIWA", "Jaco", "Gen3", "Panda")
OBJECTS = ("box", "hollow_box", "plate", "dumbbell")
OBSTACLES = ("no_obstacle", "object_wall", "object_door", "goal_wall")
OBJECTIVES = ("pick_place", "push", "trash_can", "shelf")
# Every objective on every robot; the object and obstacle rotate so each appears on each robot.
EVERY_ROBOT_AND_OBJECTIVE = [f"{r}/{OBJECTS[(i + j) % 4]}/{OBSTACLES[(i + 2 * j) % 4]}/{o}"
                             for i, r in enumerate(ROBOTS) for j, o in enumerate(OBJECTIVES)]
# What a reset's info says about the suite rather than the episode: its own episode counter
# and clock, which go on across the episodes a suite has run before.
SUITE_KEYS = ("episode", "suite_time")


def actions_for(seed: int, count: int) -> np.ndarray:
    return np.random.default_rng(seed).uniform(-1, 1, size=(count, 8))


def assert_same_info(got: dict, want: dict, where: str) -> None:
    assert got.keys() == want.keys(), where
    for key in got:
        if isinstance(want[key], float):
            assert float_bits([got[key]]) == float_bits([want[key]]), f"{where}: info[{key!r}]"
        elif isinstance(want[key], dict):
            assert list(got[key]) == list(want[key]), f"{where}: info[{key!r}]"
            assert float_bits(got[key].values()) == float_bits(want[key].values()), f"{where}: info[{key!r}]"
        else:
            assert got[key] == want[key] and type(got[key]) is type(want[key]), f"{where}: info[{key!r}]"


def run_episodes(env: gymnasium.Env, seed: int, actions: np.ndarray) -> list[tuple]:
    """Reset with `seed`, step `actions`, resetting (the env's next seed) whenever an episode
    ends: every (observation, reward, terminated, truncated, info), resets included."""
    observation, info = env.reset(seed=seed)
    trace = [(observation, 0.0, False, False, {k: v for k, v in info.items() if k not in SUITE_KEYS})]
    for action in actions:
        observation, reward, terminated, truncated, info = env.step(action)
        trace.append((observation, reward, terminated, truncated, info))
        if terminated or truncated:
            observation, info = env.reset()
            trace.append((observation, 0.0, False, False,
                          {k: v for k, v in info.items() if k not in SUITE_KEYS}))
    return trace


@pytest.fixture(scope="module")
def suite(tmp_path_factory):
    with launch_running(tmp_path_factory.mktemp("native"), "/native", TASKS[0], "--horizon",
                        str(HORIZON), service_mapping="fastdds") as launched:
        yield launched


@pytest.mark.parametrize("task", EVERY_ROBOT_AND_OBJECTIVE)
def test_native_equals_the_rust_env_and_the_ros_env_bit_for_bit(suite, task):
    actions = actions_for(7, HORIZON + 12)  # the horizon, a reset, and 11 steps of the next episode
    native = run_episodes(CompoSuiteNativeEnv(task, horizon=HORIZON), 11, actions)
    with composuite_ros.CompoSuiteRosEnv(task, "/native") as ros_env:
        over_ros = run_episodes(ros_env, 11, actions)
    assert len(native) == len(over_ros) == len(actions) + 2
    for step, (mine, theirs) in enumerate(zip(native, over_ros)):
        where = f"{task} row {step}"
        assert float_bits(mine[0]) == float_bits(theirs[0]), f"{where}: observation"
        assert float_bits([mine[1]]) == float_bits([theirs[1]]), f"{where}: reward"
        assert mine[2:4] == theirs[2:4] and all(type(v) is bool for v in mine[2:4]), f"{where}: flags"
        assert_same_info(mine[4], theirs[4], where)
    # The first episode against the Rust Env itself.
    expected = env_replay_run({"task": task, "seed": 11, "horizon": HORIZON,
                               "commands": [{"reference": [float(a) for a in action]} for action in actions[:HORIZON]]})
    assert len(expected) == HORIZON + 1
    for step, want in enumerate(expected):
        assert float_bits(native[step][0]) == float_bits(want["flat"]), f"{task} step {step}"
        assert float_bits([native[step][1]]) == float_bits([want["reward"]]), f"{task} step {step}"
        assert native[step][2:4] == (want["terminated"], want["truncated"]), f"{task} step {step}"
    assert native[HORIZON][3] and native[HORIZON][4]["reason"] == f"the horizon of {HORIZON} steps was reached"


def test_absolute_mode_equals_the_ros_env_and_the_rust_env(suite):
    task = TASKS[3]
    native = CompoSuiteNativeEnv(task, action_mode="absolute", use_task_id_obs=False, horizon=HORIZON)
    with composuite_ros.CompoSuiteRosEnv(task, "/native", action_mode="absolute",
                                         use_task_id_obs=False) as ros_env:
        assert native.observation_space == ros_env.observation_space
        assert float_bits(native.action_space.low) == float_bits(ros_env.action_space.low)
        assert float_bits(native.action_space.high) == float_bits(ros_env.action_space.high)
        low, high = native.action_space.low, native.action_space.high
        observation, _ = native.reset(seed=5)
        ros_observation, _ = ros_env.reset(seed=5)
        assert float_bits(observation) == float_bits(ros_observation)
        home = np.arctan2(observation[52:59], observation[45:52])
        rng = np.random.default_rng(1)
        commands, observations = [], [observation]
        for step in range(15):
            targets = np.clip(np.append(home + rng.uniform(-0.2, 0.2, 7), rng.uniform(low[7], high[7])),
                              low, high)
            mine, theirs = native.step(targets), ros_env.step(targets)
            assert float_bits(mine[0]) == float_bits(theirs[0]), f"step {step}"
            assert float_bits([mine[1]]) == float_bits([theirs[1]]), f"step {step}"
            assert_same_info(mine[4], theirs[4], f"step {step}")
            observations.append(mine[0])
            commands.append({"joints": targets[:7].tolist(), "gripper": None, "finger": float(targets[7])})
    expected = env_replay_run({"task": task, "seed": 5, "horizon": HORIZON, "commands": commands,
                               "task_observation": False})
    assert [float_bits(o) for o in observations] == [float_bits(e["flat"]) for e in expected]


def test_registered_and_checked_by_gymnasium():
    env = gymnasium.make("composuite_ros/CompoSuiteNative-v0", task=TASKS[1])
    assert env.observation_space.shape == (93,) and env.observation_space.dtype == np.float64
    assert env.action_space.shape == (8,) and env.action_space.dtype == np.float32
    check_env(env.unwrapped, skip_render_check=True)
    envs = gymnasium.make_vec("composuite_ros/CompoSuiteNative-v0", num_envs=3, tasks=TASKS[2])
    assert isinstance(envs, CompoSuiteNativeVectorEnv) and envs.num_envs == 3
    assert envs.observation_space.shape == (3, 93) and envs.action_space.shape == (3, 8)
    assert [str(t) for t in envs.tasks] == [TASKS[2]] * 3


def test_reward_options_and_77_observations():
    actions = actions_for(3, 15)
    for options, config in (({"reward_scale": 2.5}, {"reward_scale": 2.5}),
                            ({"reward_shaping": False}, {"reward_shaping": False}),
                            ({"use_task_id_obs": False}, {"task_observation": False})):
        env = CompoSuiteNativeEnv(TASKS[0], horizon=15, **options)
        trace = run_episodes(env, 2, actions)[:16]
        expected = env_replay_run({"task": TASKS[0], "seed": 2, "horizon": 15, **config,
                                   "commands": [{"reference": [float(a) for a in action]} for action in actions]})
        assert [float_bits(row[0]) for row in trace] == [float_bits(e["flat"]) for e in expected], options
        assert float_bits([row[1] for row in trace[1:]]) == float_bits([e["reward"] for e in expected[1:]]), options


def vector_trace(envs, seed: int, actions: np.ndarray) -> list[tuple]:
    observations, infos = envs.reset(seed=seed)
    trace = [(observations, np.zeros(envs.num_envs), np.zeros(envs.num_envs, bool),
              np.zeros(envs.num_envs, bool), infos)]
    for action in actions:
        trace.append(envs.step(action))
    return trace


def assert_same_vector_info(got: dict, want: dict, where: str) -> None:
    assert sorted(got) == sorted(want), f"{where}: keys {sorted(got)} vs {sorted(want)}"
    for key in want:
        if isinstance(want[key], dict):
            assert_same_vector_info(got[key], want[key], f"{where}.{key}")
        else:
            g, w = np.asarray(got[key]), np.asarray(want[key])
            assert g.dtype == w.dtype and g.shape == w.shape, f"{where}: {key} {g.dtype}{g.shape} vs {w.dtype}{w.shape}"
            if g.dtype.kind == "f":
                assert float_bits(g) == float_bits(w), f"{where}: {key}"
            else:
                assert g.tolist() == w.tolist(), f"{where}: {key}"


def test_vector_env_equals_each_task_alone_and_resets_next_step():
    tasks = TASKS + TASKS[:2]
    horizon = 12
    envs = CompoSuiteNativeVectorEnv(tasks, threads=2, horizon=horizon)
    steps = 2 * horizon + 3
    actions = np.stack([actions_for(100 + i, steps) for i in range(len(tasks))], axis=1)
    trace = vector_trace(envs, 40, actions)
    singles = [CompoSuiteNativeEnv(task, horizon=horizon) for task in tasks]
    first = [env.reset(seed=40 + i) for i, env in enumerate(singles)]
    expected_obs = np.stack([obs for obs, _ in first])
    assert float_bits(trace[0][0].ravel()) == float_bits(expected_obs.ravel())
    want_info: dict = {}
    for i, (_, info) in enumerate(first):
        want_info = envs._add_info(want_info, info, i)
    assert_same_vector_info(trace[0][4], want_info, "reset")
    ended = np.zeros(len(tasks), bool)
    autoreset_rows = 0
    for t in range(steps):
        observations, rewards, terminations, truncations, infos = trace[t + 1]
        want_info = {}
        for i, env in enumerate(singles):
            if ended[i]:
                # Next-step autoreset: the action is ignored, the env's next seed starts an episode.
                obs, info = env.reset()
                reward, terminated, truncated = 0.0, False, False
                autoreset_rows += 1
            else:
                obs, reward, terminated, truncated, info = env.step(actions[t, i])
            where = f"step {t} env {i}"
            assert float_bits(observations[i]) == float_bits(obs), where
            assert float_bits([rewards[i]]) == float_bits([reward]), where
            assert (bool(terminations[i]), bool(truncations[i])) == (terminated, truncated), where
            want_info = envs._add_info(want_info, info, i)
        assert_same_vector_info(infos, want_info, f"step {t}")
        ended = terminations | truncations
    assert autoreset_rows == 2 * len(tasks), "every environment autoreset twice"


def test_results_do_not_depend_on_the_threads():
    tasks = TASKS * 2
    actions = np.stack([actions_for(200 + i, 25) for i in range(len(tasks))], axis=1)
    one = vector_trace(CompoSuiteNativeVectorEnv(tasks, threads=1, horizon=10), 3, actions)
    two = vector_trace(CompoSuiteNativeVectorEnv(tasks, threads=2, horizon=10), 3, actions)
    for t, (a, b) in enumerate(zip(one, two)):
        for part in range(4):
            assert float_bits(np.ravel(a[part])) == float_bits(np.ravel(b[part])), f"step {t} part {part}"
        assert_same_vector_info(a[4], b[4], f"step {t}")


def test_copy_false_returns_the_batch_buffers():
    envs = CompoSuiteNativeVectorEnv(TASKS[0], num_envs=2, copy=False)
    first, _ = envs.reset(seed=0)
    again, _ = envs.reset(seed=1)
    assert first is again  # the same buffer, overwritten
    envs_copying = CompoSuiteNativeVectorEnv(TASKS[0], num_envs=2)
    a, _ = envs_copying.reset(seed=0)
    b, _ = envs_copying.reset(seed=1)
    assert a is not b and not np.array_equal(a, b)


def test_bad_input_is_named():
    with pytest.raises(ValueError, match="valid.*IIWA, Jaco, Gen3, Panda"):
        CompoSuiteNativeEnv("Baxter/box/no_obstacle/pick_place")
    with pytest.raises(ValueError, match="robot/object/obstacle/objective"):
        CompoSuiteNativeEnv("IIWA/box")
    with pytest.raises(ValueError, match="action_mode"):
        CompoSuiteNativeEnv(action_mode="torque")
    env = CompoSuiteNativeEnv(TASKS[0], horizon=2)
    with pytest.raises(EpisodeOverError, match="reset"):
        env.step(np.zeros(8))
    env.reset(seed=0)
    with pytest.raises(ValueError, match="has 7 values; this env takes 8"):
        env.step(np.zeros(7))
    with pytest.raises(ValueError, match="non-finite"):
        env.step([0, 0, np.nan, 0, 0, 0, 0, 0])
    with pytest.raises(ValueError, match="seed .* is out of range; valid seeds are 0..=4294967295"):
        env.reset(seed=2**40)
    env.reset(seed=0)
    env.step(np.zeros(8))
    assert env.step(np.zeros(8))[3], "truncated at the horizon of 2"
    with pytest.raises(EpisodeOverError, match="is over"):
        env.step(np.zeros(8))
    with pytest.raises(ValueError, match="3 tasks for num_envs=2"):
        CompoSuiteNativeVectorEnv(TASKS[:3], num_envs=2)
    with pytest.raises(ValueError, match="threads must be at least 1"):
        composuite_ros._native.Batch([TASKS[0]], threads=0)
    envs = CompoSuiteNativeVectorEnv(TASKS[:2])
    with pytest.raises(EpisodeOverError, match="reset"):
        envs.step(np.zeros((2, 8)))
    envs.reset(seed=0)
    with pytest.raises(ValueError, match=r"shape \(3, 8\); expected \(2, 8\)"):
        envs.step(np.zeros((3, 8)))
    with pytest.raises(IndexError, match="environment 5 does not exist; valid: 0..1"):
        envs.set_task(5, TASKS[0])


def test_set_task_switches_the_task_and_its_action_space():
    env = CompoSuiteNativeEnv(TASKS[0], action_mode="absolute")
    iiwa_high = env.action_space.high.copy()
    assert str(env.set_task("Kinova3/Plate/ObjectWall/Shelf")) == "Gen3/plate/object_wall/shelf"
    assert not np.array_equal(env.action_space.high, iiwa_high)
    observation, info = env.reset(seed=0, options={"task": TASKS[2]})
    assert info["task"] == TASKS[2] and observation[45:61].sum() == 4  # the four one-hots


def test_in_process_parts_need_no_rclpy():
    probe = """
import sys
for name in ("rclpy", "composuite_msgs", "builtin_interfaces", "sensor_msgs", "std_msgs"):
    sys.modules[name] = None  # any import of these now fails
import gymnasium, composuite_ros
env = gymnasium.make("composuite_ros/CompoSuiteNative-v0")
env.reset(seed=0)
print(env.step(env.action_space.sample())[4]["step"])
try:
    composuite_ros.CompoSuiteRosEnv
except ImportError as err:
    print("ros part:", type(err).__name__)
"""
    result = subprocess.run([sys.executable, "-c", probe], capture_output=True, text=True, timeout=120)
    assert result.returncode == 0, result.stderr
    assert result.stdout.split("\n")[:2] == ["1", "ros part: ModuleNotFoundError"]


def test_ppo_example_trains_in_process_by_default(tmp_path):
    log = tmp_path / "ppo.csv"
    result = subprocess.run(
        [sys.executable, str(REPO / "examples" / "ppo_train.py"), "--num-envs", "2", "--epochs", "2",
         "--steps-per-epoch", "60", "--pi-iters", "3", "--v-iters", "3", "--log", str(log)],
        capture_output=True, text=True, timeout=180, check=False)
    assert result.returncode == 0, result.stderr[-3000:]
    lines = log.read_text().splitlines()
    assert len(lines) == 3 and lines[2].split(",")[1] == "120", lines  # header, 2 epochs, total steps
    wrong = subprocess.run([sys.executable, str(REPO / "examples" / "ppo_train.py"), "--backend", "native",
                            "--namespaces", "/env_00"], capture_output=True, text=True, timeout=60)
    assert wrong.returncode == 2 and "--backend ros" in wrong.stderr


def test_renders_rgb_arrays_of_the_scene_as_gymnasium_expects():
    """render_mode="rgb_array": render() gives the scene through the chosen camera as an (h, w, 3)
    uint8 array — the same frame for the same state, another when the arm moves or another camera
    looks; without a render mode it gives None; bad settings are refused at construction."""
    assert CompoSuiteNativeEnv(TASKS[0], horizon=HORIZON).render() is None
    env = CompoSuiteNativeEnv(TASKS[0], horizon=HORIZON, render_mode="rgb_array",
                              render_width=96, render_height=64)
    assert env.metadata["render_fps"] == 20
    check_env(env)  # Gymnasium's own render checks included
    env.reset(seed=3)
    first = env.render()
    assert first.shape == (64, 96, 3) and first.dtype == np.uint8
    assert len(np.unique(first.reshape(-1, 3), axis=0)) > 10, "a scene, not a blank"
    assert np.array_equal(env.render(), first), "rendering changes nothing"
    for _ in range(10):
        env.step(np.array([1.0, 1.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0]))
    assert not np.array_equal(env.render(), first), "the arm moved"
    env.reset(seed=3)
    assert np.array_equal(env.render(), first), "the same state, the same frame"
    bird = CompoSuiteNativeEnv(TASKS[0], horizon=HORIZON, render_mode="rgb_array",
                               render_camera="birdview", render_width=96, render_height=64)
    bird.reset(seed=3)
    assert not np.array_equal(bird.render(), first)
    with pytest.raises(ValueError, match="frontview.*eye_in_hand"):
        CompoSuiteNativeEnv(TASKS[0], render_mode="rgb_array", render_camera="topview")
    with pytest.raises(ValueError, match="rgb_array"):
        CompoSuiteNativeEnv(TASKS[0], render_mode="human")
    with pytest.raises(ValueError):
        CompoSuiteNativeEnv(TASKS[0], render_mode="rgb_array", render_width=0)


def test_the_vector_env_renders_one_frame_per_environment():
    """render_mode="rgb_array" on the vector env: render() gives a tuple with one (h, w, 3) frame per
    environment (Gymnasium's vector convention), each the frame the single env gives for the same
    task, seed and actions, bit for bit; a bad camera is refused when made."""
    tasks = [TASKS[0], TASKS[1], TASKS[0]]
    envs = gymnasium.make_vec("composuite_ros/CompoSuiteNative-v0", num_envs=3, tasks=tasks, horizon=HORIZON,
                              render_mode="rgb_array", render_camera="agentview", render_width=80, render_height=60)
    assert envs.render_mode == "rgb_array" and envs.metadata["render_fps"] == 20
    envs.reset(seed=[5, 6, 7])
    actions = np.random.default_rng(1).uniform(-1, 1, size=(4, 3, 8))
    for a in actions:
        envs.step(a)
    frames = envs.render()
    assert isinstance(frames, tuple) and len(frames) == 3
    assert all(f.shape == (60, 80, 3) and f.dtype == np.uint8 for f in frames)
    for i, task in enumerate(tasks):
        single = CompoSuiteNativeEnv(task, horizon=HORIZON, render_mode="rgb_array", render_camera="agentview",
                                     render_width=80, render_height=60)
        single.reset(seed=5 + i)
        for a in actions:
            single.step(a[i])
        assert np.array_equal(single.render(), frames[i]), task
    assert not np.array_equal(frames[0], frames[2]), "other seeds and actions, another scene"
    envs.close()
    assert CompoSuiteNativeVectorEnv(TASKS[0], num_envs=2).render() is None
    with pytest.raises(ValueError, match="frontview.*eye_in_hand"):
        CompoSuiteNativeVectorEnv(TASKS[0], num_envs=2, render_mode="rgb_array", render_camera="top")


def test_a_frame_drawn_from_the_observation_alone_matches_the_envs_frame():
    """_native.StateRenderer (what CompoSuiteRosEnv renders with) draws the scene from a flat
    observation; it shows what the env's own render shows, up to a few edge pixels."""
    from composuite_ros import _native

    for with_task in (True, False):
        env = CompoSuiteNativeEnv(TASKS[2], horizon=HORIZON, use_task_id_obs=with_task, render_mode="rgb_array",
                                  render_width=96, render_height=96)
        observation, _ = env.reset(seed=4)
        for _ in range(8):
            observation, *_ = env.step(np.array([0.5, -0.5, 0.3, 0.8, -0.2, 0.4, 0.1, 1.0]))
        drawn = _native.StateRenderer(TASKS[2]).render(observation, "frontview", 96, 96)
        differ = np.any(np.abs(drawn.astype(int) - env.render().astype(int)) > 2, axis=2).mean()
        assert differ < 0.01, differ
    assert _native.task_of_one_hots(list(observation_one_hots(TASKS[2]))) == TASKS[2]
    with pytest.raises(ValueError, match="93.*77"):
        _native.StateRenderer(TASKS[2]).render(np.zeros(10), "frontview", 8, 8)
    with pytest.raises(ValueError, match="one-hots"):
        _native.task_of_one_hots([0.0] * 16)


def observation_one_hots(task: str) -> np.ndarray:
    env = CompoSuiteNativeEnv(task, horizon=HORIZON)
    observation, _ = env.reset(seed=0)
    return observation[45:61]


def test_gymnasiums_record_video_writes_the_episodes(tmp_path):
    """Gymnasium's RecordVideo (single env) and its vector RecordVideo (the environments' frames
    tiled) write MP4s through moviepy; imageio reads them back: one frame per observation."""
    import imageio.v3 as iio
    from gymnasium.wrappers import RecordVideo
    from gymnasium.wrappers.vector import RecordVideo as VectorRecordVideo

    env = RecordVideo(gymnasium.make("composuite_ros/CompoSuiteNative-v0", task=TASKS[1], horizon=12,
                                     render_mode="rgb_array", render_width=64, render_height=48),
                      str(tmp_path / "one"), episode_trigger=lambda e: True, disable_logger=True)
    env.reset(seed=2)
    done = False
    while not done:
        _, _, terminated, truncated, _ = env.step(env.action_space.sample())
        done = terminated or truncated
    env.close()
    (video,) = (tmp_path / "one").glob("*.mp4")
    frames = np.stack(list(iio.imiter(video, plugin="FFMPEG")))
    assert frames.shape == (13, 48, 64, 3), "the reset and 12 steps"
    assert not np.array_equal(frames[0], frames[-1])

    envs = VectorRecordVideo(
        gymnasium.make_vec("composuite_ros/CompoSuiteNative-v0", num_envs=2, horizon=8, render_mode="rgb_array",
                           render_width=32, render_height=32),
        str(tmp_path / "vec"), episode_trigger=lambda e: e == 0, disable_logger=True)
    envs.reset(seed=0)
    for _ in range(6):
        envs.step(envs.action_space.sample())
    envs.close()
    (video,) = (tmp_path / "vec").glob("*.mp4")
    frames = np.stack(list(iio.imiter(video, plugin="FFMPEG")))
    assert frames.shape[1:] == (32, 64, 3), "two environments side by side"
    assert frames.shape[0] == 7, "the reset and 6 steps"
