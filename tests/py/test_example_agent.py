"""examples/lockstep_agent.py — the rclpy agent the docs point users to — against a running
suite: as a library (reset, steps, observations bit-identical to the in-process reference) and as
a script. Only run inside scripts/netns-isolate."""

import importlib.util
import math
import os
import subprocess
import sys

import pytest

import node_suite
from node_suite import env_replay_run, float_bits

EXAMPLE = node_suite.REPO / "examples" / "lockstep_agent.py"
NS = "/ex"
TASK = "IIWA/box/no_obstacle/pick_place"


@pytest.fixture(scope="module")
def domain() -> int:
    return node_suite.random_domain()


@pytest.fixture(scope="module")
def suite(tmp_path_factory, domain):
    with node_suite.running(tmp_path_factory.mktemp("example_logs"), NS, domain,
                            task_manager={"task": TASK}) as s:
        yield s


def load_example():
    spec = importlib.util.spec_from_file_location("lockstep_agent", EXAMPLE)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def test_the_example_env_steps_exactly_like_the_in_process_env(suite, domain):
    example = load_example()
    env = example.LockstepEnv(NS, domain_id=domain, timeout=25.0)
    try:
        first = env.reset(seed=4)
        home = [math.atan2(s, c) for s, c in zip(first.robot.joint_pos_sin, first.robot.joint_pos_cos)]
        commands, flats, rewards = [], [list(first.flat)], []
        for k in range(30):
            targets = [q + 0.01 * ((k * 7 + j) % 5 - 2) for j, q in enumerate(home)]
            observation, reward, terminated, truncated, info = env.step(targets)
            assert not terminated and not truncated
            assert set(info["stages"]) == {"reach", "grasp", "lift", "hover", "drop"}
            commands.append({"joints": targets, "gripper": None})
            flats.append(list(observation.flat))
            rewards.append(reward)
        assert env.step_count == 30
    finally:
        env.close()
    reference = env_replay_run({"task": TASK, "seed": 4, "commands": commands})
    assert [float_bits(f) for f in flats] == [float_bits(r["flat"]) for r in reference]
    assert float_bits(rewards) == float_bits([r["reward"] for r in reference[1:]])


def test_the_example_runs_as_a_script(suite, domain):
    env = dict(os.environ, ROS_DOMAIN_ID=str(domain))
    result = subprocess.run([sys.executable, str(EXAMPLE), "--namespace", NS, "--episodes", "2",
                             "--steps", "20"], env=env, capture_output=True, text=True, timeout=120)
    assert result.returncode == 0, result.stderr
    lines = [l for l in result.stdout.splitlines() if l.startswith("episode ")]
    assert len(lines) == 2 and all(" 20 steps" in l for l in lines), result.stdout
