"""The `composuite_ros` Gymnasium package (python/) against `composuite launch`, with the real
rclpy from ROS 2 Jazzy on Fast DDS: Gymnasium's own env checker, bit-identical episodes against
the in-process `Env` (env_replay) in both action modes, the vector env over 4 environments with
2 tasks, autoreset, and every error the package promises."""

from __future__ import annotations

import csv
import subprocess
import sys
import threading

import gymnasium
import numpy as np
import pytest
from gymnasium.utils.env_checker import check_env

from node_suite import REPO, env_replay_run, float_bits, launch_running

import composuite_ros
from composuite_ros import CompoSuiteRosEnv, EpisodeOverError, StepLostError, SuiteNotRunningError
from composuite_ros.vector import CompoSuiteRosVectorEnv

HORIZON = 40
# One task per objective (and every robot): what the bit-identity test runs.
TASKS = ["IIWA/box/no_obstacle/pick_place", "Jaco/dumbbell/object_wall/push",
         "Gen3/plate/goal_wall/trash_can", "Panda/hollow_box/object_door/shelf"]


@pytest.fixture(scope="module")
def suite(tmp_path_factory):
    with launch_running(tmp_path_factory.mktemp("gym"), "/gym", TASKS[0], "--horizon", str(HORIZON),
                        service_mapping="fastdds") as launched:
        yield launched


@pytest.fixture(scope="module")
def env(suite):
    environment = gymnasium.make("composuite_ros/CompoSuite-v0", task=TASKS[0], namespace="/gym")
    yield environment
    environment.close()


def replay(task: str, seed: int, commands: list[dict], **config) -> list[dict]:
    return env_replay_run({"task": task, "seed": seed, "horizon": HORIZON, "commands": commands, **config})


def test_registered_and_spaces(env):
    assert "composuite_ros/CompoSuite-v0" in gymnasium.registry
    assert env.observation_space.shape == (93,) and env.observation_space.dtype == np.float64
    assert env.action_space.shape == (8,)
    assert np.all(env.action_space.low == -1) and np.all(env.action_space.high == 1)


def test_gymnasium_env_checker(env):
    # Reset determinism, spaces, step return types, seeding: Gymnasium's own checks.
    check_env(env.unwrapped, skip_render_check=True)


@pytest.mark.parametrize("task", TASKS)
def test_episode_bit_identical_to_in_process_env(env, task):
    env.unwrapped.set_task(task)
    rng = np.random.default_rng(7)
    actions = rng.uniform(-1, 1, size=(HORIZON, 8))
    observation, info = env.reset(seed=11)
    assert info["seed"] == 11
    got = [(observation, 0.0, False, False)]
    for action in actions:
        observation, reward, terminated, truncated, info = env.step(action)
        got.append((observation, reward, terminated, truncated))
        if terminated or truncated:
            break
    assert set(info["stages"]) >= {"reach", "grasp"}
    expected = replay(task, 11, [{"reference": [float(a) for a in action]} for action in actions])
    assert len(got) == len(expected), "episode lengths differ"
    for step, ((obs, reward, terminated, truncated), want) in enumerate(zip(got, expected)):
        assert float_bits(obs) == float_bits(want["flat"]), f"{task}: observation of step {step} differs"
        assert float_bits([reward]) == float_bits([want["reward"]]), f"{task}: reward of step {step}"
        assert (terminated, truncated) == (want["terminated"], want["truncated"]), f"{task}: step {step}"
    # The horizon truncates (no objective ends these random episodes early).
    assert got[-1][3] and len(got) == HORIZON + 1


@pytest.mark.parametrize("options,config", [
    (("--reward-scale", "2.5"), {"reward_scale": 2.5}),
    (("--sparse-rewards",), {"reward_shaping": False}),
])
def test_reward_shaping_and_scale_options_equal_the_in_process_env(tmp_path, options, config):
    """The reference's make(reward_shaping=..., reward_scale=...) as launch options (reward node
    parameters): the rewards equal the in-process Env's with the same settings, bit for bit,
    while the stages are still reported."""
    task = TASKS[0]
    with launch_running(tmp_path, "/shaping", task, "--horizon", "15", *options, service_mapping="fastdds"):
        with CompoSuiteRosEnv(task=task, namespace="/shaping") as environment:
            actions = np.random.default_rng(3).uniform(-1, 1, size=(15, 8))
            environment.reset(seed=2)
            rewards, stages = [], []
            for action in actions:
                _, reward, _, _, info = environment.step(action)
                rewards.append(reward)
                stages.append(max(info["stages"].values()))
    expected = env_replay_run({"task": task, "seed": 2, "horizon": 15, **config,
                               "commands": [{"reference": [float(a) for a in action]} for action in actions]})
    assert float_bits(rewards) == float_bits([step["reward"] for step in expected[1:]])
    assert max(stages) > 0, "the reach stage is non-zero somewhere"
    if config.get("reward_shaping") is False:
        assert rewards == [0.0] * len(rewards), "no success in 15 random steps: sparse rewards are 0"
    else:
        assert rewards == [2.5 * s for s in stages]


def test_absolute_mode_and_77_observations(suite):
    task = TASKS[3]
    env = CompoSuiteRosEnv(task, "/gym", action_mode="absolute", use_task_id_obs=False)
    try:
        assert env.observation_space.shape == (77,)
        low, high = env.action_space.low, env.action_space.high
        assert low.shape == (8,) and np.all(low < high) and high[7] < 0.1  # a finger joint, in m
        observation, _ = env.reset(seed=5)
        rng = np.random.default_rng(1)
        home = np.arctan2(observation[52:59], observation[45:52])  # sin, cos of the 7 joints
        commands, observations = [], [observation]
        for _ in range(15):
            targets = np.clip(np.append(home + rng.uniform(-0.2, 0.2, 7), rng.uniform(low[7], high[7])),
                              low, high)
            observations.append(env.step(targets)[0])
            commands.append({"joints": targets[:7].tolist(), "gripper": None, "finger": float(targets[7])})
    finally:
        env.close()
    expected = replay(task, 5, commands, task_observation=False)
    assert [float_bits(o) for o in observations] == [float_bits(e["flat"]) for e in expected]


def test_seeds_continue_deterministically(env):
    env.unwrapped.set_task(TASKS[0])
    env.reset(seed=3)
    second = env.reset()[1]["seed"]
    third = env.reset()[1]["seed"]
    env.reset(seed=3)
    assert [env.reset()[1]["seed"], env.reset()[1]["seed"]] == [second, third]
    assert len({3, second, third}) == 3


def test_errors_say_what_was_wrong(env, suite):
    with pytest.raises(ValueError, match="valid"):
        env.unwrapped.set_task("IIWA/box/no_obstacle/fly")
    with pytest.raises(ValueError, match="robot/object/obstacle/objective"):
        env.unwrapped.set_task("IIWA/box")
    env.unwrapped.set_task(TASKS[0])
    env.reset(seed=0)
    with pytest.raises(ValueError, match="8"):
        env.unwrapped.step(np.zeros(7))
    with pytest.raises(ValueError, match="non-finite"):
        env.unwrapped.step(np.full(8, np.nan))
    for _ in range(HORIZON):
        env.step(np.zeros(8))
    with pytest.raises(EpisodeOverError, match="reset"):
        env.unwrapped.step(np.zeros(8))
    with pytest.raises(ValueError, match="action_mode"):
        CompoSuiteRosEnv(TASKS[0], "/gym", action_mode="torque")


def test_suite_not_running_names_the_namespace(suite):
    with pytest.raises(SuiteNotRunningError, match="/nobody_here"):
        CompoSuiteRosEnv(TASKS[0], "/nobody_here", timeout=1.5)


def test_close_leaves_no_thread_or_endpoint(env, suite):
    # The module's `env` fixture is alive and publishes on the same topic: wait until the new probe
    # has discovered it, so the baseline is known (1) rather than whatever discovery reached so far.
    before = threading.active_count()
    probe = composuite_ros._link.Participant("probe")
    try:
        topic = "/gym/reference_action_stamped"
        baseline = 1
        assert probe.spin_for(lambda: probe.node.count_publishers(topic) == baseline, 20.0), \
            "the probe never discovered the module env's publisher"
        closing = CompoSuiteRosEnv(TASKS[0], "/gym")
        assert probe.spin_for(lambda: probe.node.count_publishers(topic) == baseline + 1, 20.0)
        closing.reset(seed=1)
        closing.step(np.zeros(8))
        closing.close()
        assert not closing._participant.context.ok()
        # Gone from the graph: at once when the participant's goodbye arrives, else after the
        # DDS lease (Fast DDS: 20 s).
        assert probe.spin_for(lambda: probe.node.count_publishers(topic) == baseline, 30.0), \
            "the closed env's publisher is still in the graph"
    finally:
        probe.close()
    assert threading.active_count() == before


def test_lost_step_names_it(tmp_path):
    # A sim killed mid-episode: the step in flight is lost; the error says which one.
    with launch_running(tmp_path, "/lost", TASKS[0], "--respawn-delay", "30",
                        service_mapping="fastdds") as launched:
        env = CompoSuiteRosEnv(TASKS[0], "/lost")
        try:
            env.reset(seed=0)
            env.timeout = 2.0
            for _ in range(3):
                env.step(np.zeros(8))
            launched.kill_node("sim")
            with pytest.raises(StepLostError, match="step 4 of episode"):
                env.step(np.zeros(8))
        finally:
            env.close()


def test_vector_env_four_environments_two_tasks(tmp_path):
    tasks = [TASKS[0], TASKS[1]] * 2
    with launch_running(tmp_path, "/vec", TASKS[0], "--envs", "4", "--horizon", "12",
                        service_mapping="fastdds") as launched:
        envs = CompoSuiteRosVectorEnv(launched.namespaces, tasks, render_mode="rgb_array", render_width=48,
                                      render_height=32)
        try:
            observations, infos = envs.reset(seed=20)
            assert observations.shape == (4, 93) and list(infos["seed"]) == [20, 21, 22, 23]
            rng = np.random.default_rng(3)
            actions = rng.uniform(-1, 1, size=(14, 4, 8))
            trace = [observations]
            rewards, ends = [], []
            for step_actions in actions:
                observations, reward, terminated, truncated, infos = envs.step(step_actions)
                trace.append(observations)
                rewards.append(reward)
                ends.append(terminated | truncated)
            frames = envs.render()
        finally:
            envs.close()
    # One frame per environment: its last observation drawn (what the native module draws from it).
    from composuite_ros import _native

    assert isinstance(frames, tuple) and len(frames) == 4
    for i in range(4):
        assert frames[i].shape == (32, 48, 3)
        assert np.array_equal(frames[i], _native.StateRenderer(tasks[i]).render(trace[-1][i], "frontview", 48, 32))
    # Each environment equals its own in-process Env: 12 steps, the horizon ends it (step 12),
    # step 13 is the autoreset (new episode's first observation, reward 0), step 14 its step 1.
    for i in range(4):
        expected = env_replay_run({"task": tasks[i], "seed": 20 + i, "horizon": 12,
                                   "commands": [{"reference": a.tolist()} for a in actions[:12, i]]})
        assert [float_bits(trace[t][i]) for t in range(13)] == [float_bits(e["flat"]) for e in expected]
        assert float_bits([r[i] for r in rewards[:12]]) == float_bits([e["reward"] for e in expected[1:]])
        assert [bool(e[i]) for e in ends[:13]] == [False] * 11 + [True, False]
        assert rewards[12][i] == 0.0
    # The different tasks really are different environments (their task one-hots differ).
    assert not np.array_equal(trace[0][0][45:61], trace[0][1][45:61])
    assert np.array_equal(trace[0][0][45:61], trace[0][2][45:61])


def test_ppo_example_trains_through_the_vector_env(tmp_path):
    # The numpy PPO of examples/ (the paper's learner) on two environments of the suite: it steps,
    # updates and logs (no learning claim in so few steps).
    log, saved = tmp_path / "ppo.csv", tmp_path / "ppo.npz"
    with launch_running(tmp_path, "/ppo", TASKS[0], "--envs", "2", "--horizon", "25",
                        service_mapping="fastdds") as launched:
        result = subprocess.run(
            [sys.executable, str(REPO / "examples" / "ppo_train.py"), "--namespaces", ",".join(launched.namespaces),
             "--epochs", "2", "--steps-per-epoch", "60", "--pi-iters", "3", "--v-iters", "3",
             "--log", str(log), "--save", str(saved)],
            capture_output=True, text=True, timeout=180, check=False)
    assert result.returncode == 0, result.stderr[-3000:]
    with open(log) as f:
        rows = list(csv.DictReader(f))
    assert [int(r["total_steps"]) for r in rows] == [60, 120]
    # 2 envs × 60 steps: each env finishes 25-step episodes (the reset steps count as steps).
    assert int(rows[0]["episodes"]) + int(rows[1]["episodes"]) >= 4
    assert all(np.isfinite(float(r["ep_return_mean"])) for r in rows if r["ep_return_mean"])
    # The suite reports success, so the success column is filled once episodes finish.
    assert all(r["success_rate"] != "" for r in rows if int(r["episodes"]))
    parameters = np.load(saved)
    assert parameters["pi/W0"].shape == (93, 64) and parameters["log_std"].shape == (8,)


def test_renders_the_scene_of_each_observation(suite, tmp_path):
    """render_mode="rgb_array" over ROS: render() draws the last observation the suite sent, in
    this process; Gymnasium's checker (render checks included, which make a second env through
    the spec) passes; the frames are exactly what the native module draws from the in-process
    env's (bit-identical) observations, and within a few edge pixels of its own render()."""
    from composuite_ros import _native

    env = gymnasium.make("composuite_ros/CompoSuite-v0", task=TASKS[0], namespace="/gym", render_mode="rgb_array",
                         render_camera="sideview", render_width=72, render_height=48)
    try:
        assert env.unwrapped.metadata["render_fps"] == 20
        with pytest.raises(gymnasium.error.ResetNeeded):
            env.unwrapped.render()
        check_env(env.unwrapped)
        native = composuite_ros.CompoSuiteNativeEnv(TASKS[0], horizon=HORIZON, render_mode="rgb_array",
                                                    render_camera="sideview", render_width=72, render_height=48)
        observation, _ = env.reset(seed=11)
        expected, _ = native.reset(seed=11)
        drawer = _native.StateRenderer(TASKS[0])
        frames = [env.render()]
        assert np.array_equal(frames[0], drawer.render(expected, "sideview", 72, 48))
        for k in range(6):
            action = np.array([0.6, 0.6, -0.4, 0.5, 0.0, 0.3, 0.0, 1.0 if k > 2 else -1.0])
            env.step(action)
            expected, *_ = native.step(action)
            frames.append(env.render())
            assert frames[-1].shape == (48, 72, 3) and frames[-1].dtype == np.uint8
            assert np.array_equal(frames[-1], drawer.render(expected, "sideview", 72, 48))
            differ = np.any(np.abs(frames[-1].astype(int) - native.render().astype(int)) > 2, axis=2).mean()
            assert differ < 0.01
        assert not np.array_equal(frames[0], frames[-1]), "the arm moved"
    finally:
        env.close()
    # Gymnasium's RecordVideo on the env over ROS: an MP4 of the episode, read back by imageio.
    import imageio.v3 as iio
    from gymnasium.wrappers import RecordVideo

    recorded = RecordVideo(gymnasium.make("composuite_ros/CompoSuite-v0", task=TASKS[0], namespace="/gym",
                                          render_mode="rgb_array", render_width=48, render_height=48),
                           str(tmp_path / "videos"), episode_trigger=lambda e: True, disable_logger=True)
    try:
        recorded.reset(seed=4)
        for _ in range(5):
            recorded.step(recorded.action_space.sample())
    finally:
        recorded.close()
    (video,) = (tmp_path / "videos").glob("*.mp4")
    assert np.stack(list(iio.imiter(video, plugin="FFMPEG"))).shape == (6, 48, 48, 3)
    with pytest.raises(ValueError, match="frontview.*eye_in_hand"):
        CompoSuiteRosEnv(TASKS[0], namespace="/gym", render_mode="rgb_array", render_camera="wrist")
