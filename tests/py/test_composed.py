"""The composed suite: `composuite launch --envs 3` runs every environment's nodes in its own
process on one DDS participant. Checked with real rclpy on Fast DDS: the nine nodes are ROS
nodes in the graph (`ros2 node list`), no node process exists (the launcher's threads are the
nodes), each environment steps bit-identical to the in-process env, and a node that fails (the
sim's `fault_panic` parameter) takes down only its environment, which launch starts again
while the others go on stepping. The standard simulation interfaces (simulation_interfaces) answer
in every environment's namespace as they do for separate processes. `--processes 2` splits the
environments over two child processes; a SIGKILL of one restarts its share only. The physics runs
on the `--threads` asked for, and each environment's sim hands world_state to its reward node in
the process: the reward node scores each step once, and an outside reader still gets every step."""

from __future__ import annotations

import os
import signal
import time
from pathlib import Path

import numpy as np
import pytest
from rcl_interfaces.msg import Parameter, ParameterType, ParameterValue
from rcl_interfaces.srv import SetParameters

import node_suite
from node_suite import float_bits, launch_running
from rclpy_agent import RclpyAgent

from composuite_ros import CompoSuiteNativeEnv, CompoSuiteRosEnv

NS = "/cmp"
ENVS = 3
TASK = "IIWA/box/no_obstacle/pick_place"
NAMESPACES = [f"{NS}/env_{i:02}" for i in range(ENVS)]


@pytest.fixture(scope="module")
def suite(tmp_path_factory):
    with launch_running(tmp_path_factory.mktemp("composed"), NS, TASK, "--envs", str(ENVS),
                        "--respawn", "2", "--respawn-delay", "0.5", "--threads", "2",
                        service_mapping="fastdds") as launched:
        yield launched


def thread_names(pid: int) -> list[str]:
    return [(task / "comm").read_text().strip() for task in Path(f"/proc/{pid}/task").iterdir()]


def test_one_process_whose_threads_are_the_nodes(suite):
    assert "in this process (one DDS participant)" in suite.text()
    assert node_suite.node_processes(f"__ns:={NS}") == [], "no node runs as a process of its own"
    threads = thread_names(suite.process.pid)
    for i in range(ENVS):
        for node in ("sim", "task_manager", "reward"):
            assert f"{node}-{i}" in threads, sorted(threads)


def test_the_physics_runs_on_the_threads_asked_for(suite):
    steppers = sorted(t for t in thread_names(suite.process.pid) if t.startswith("env-step-"))
    assert steppers == ["env-step-0", "env-step-1"]


def spin_for(agent: RclpyAgent, seconds: float) -> None:
    end = time.monotonic() + seconds
    while time.monotonic() < end:
        agent.executor.spin_once(timeout_sec=0.05)


def last_episode_steps(seen: list[tuple[int, int]]) -> list[int]:
    """The steps of the latest episode among (episode, step) pairs."""
    latest = max((number for number, _ in seen), default=None)
    return [step for number, step in seen if number == latest]


def test_each_step_is_handed_over_once_in_the_process_and_still_goes_on_the_wire(suite):
    from composuite_msgs.msg import StagedReward, WorldState
    ns = NAMESPACES[1]
    suite.wait_for_log(f"{ns}/reward up; world_state handed over in this process")
    suite.wait_for_log(f"{ns}/task_manager up: task {TASK}, services in the fastdds format; "
                       "world_state and observation handed over in this process")
    agent = RclpyAgent(suite.domain)
    worlds, rewards = [], []
    try:
        agent.node.create_subscription(WorldState, f"{ns}/world_state",
                                       lambda m: worlds.append((m.episode, m.step)), 100)
        agent.node.create_subscription(StagedReward, f"{ns}/reward",
                                       lambda m: rewards.append((m.episode, m.step)), 100)
        for topic in ("world_state", "reward"):
            agent.spin_until(lambda: agent.node.count_publishers(f"{ns}/{topic}") > 0, 25.0,
                             f"the {topic} writer")
        # Each side sees the match on its own: give the suite's writers time to see ours.
        spin_for(agent, 1.0)
        steps = 20
        with CompoSuiteRosEnv(TASK, ns) as env:
            episode(env, 5, steps)
        every_step = list(range(steps + 1))  # the reset state and each step
        agent.spin_until(lambda: len(last_episode_steps(worlds)) >= len(every_step)
                         and len(last_episode_steps(rewards)) >= len(every_step),
                         10.0, "the episode's world states and rewards")
        spin_for(agent, 0.5)  # a duplicate would come right after its original
        assert sorted(last_episode_steps(worlds)) == every_step, "every world_state on the wire, once"
        assert sorted(last_episode_steps(rewards)) == every_step, "the reward node scored each step once"
    finally:
        agent.close()


def test_every_node_is_a_ros_node_in_the_graph(suite):
    agent = RclpyAgent(suite.domain)
    try:
        wanted = {(node, ns) for ns in NAMESPACES for node in ("sim", "task_manager", "reward")}
        agent.spin_until(lambda: wanted <= set(agent.node.get_node_names_and_namespaces()), 25.0,
                         "the nine nodes in rclpy's graph")
        # Node names (ros_discovery_info) and endpoints (DDS discovery) arrive separately.
        needed = {f"{ns}/{name}" for ns in NAMESPACES for name in ("reset", "sim/set_parameters")}
        agent.spin_until(lambda: needed <= dict(agent.node.get_service_names_and_types()).keys(),
                         25.0, "every environment's services in rclpy's graph")
        services = dict(agent.node.get_service_names_and_types())
        for ns in NAMESPACES:
            assert services[f"{ns}/reset"] == ["composuite_msgs/srv/Reset"]
            assert f"{ns}/sim/set_parameters" in services
    finally:
        agent.close()


def test_the_standard_simulation_interfaces_answer_in_every_environment(suite):
    from simulation_interfaces.msg import Result, SimulationState
    from simulation_interfaces.srv import (GetCurrentWorld, GetEntityState, GetSimulationState,
                                           GetSimulatorFeatures, StepSimulation)
    agent = RclpyAgent(suite.domain)
    try:
        for ns in NAMESPACES:
            client = lambda t, name: agent.node.create_client(t, f"{ns}/{name}")  # noqa: E731
            features = agent.call(client(GetSimulatorFeatures, "get_simulator_features"),
                                  GetSimulatorFeatures.Request()).features
            assert "CompoSuite-ROS" in features.custom_info and len(features.features) > 10
            state = agent.call(client(GetSimulationState, "get_simulation_state"), GetSimulationState.Request())
            assert state.state.state == SimulationState.STATE_PAUSED
            world = agent.call(client(GetCurrentWorld, "get_current_world"), GetCurrentWorld.Request())
            assert world.world.name == TASK
            entity = client(GetEntityState, "get_entity_state")
            before = agent.call(entity, GetEntityState.Request(entity="object")).state.header.stamp
            step = client(StepSimulation, "step_simulation")
            # A refused request first (0 steps) so that this client's replies are matched: the
            # stepping call below is then sent once.
            assert agent.call(step, StepSimulation.Request(steps=0)).result.result == Result.RESULT_OPERATION_FAILED
            done = agent.call(step, StepSimulation.Request(steps=3), attempt=10.0)
            assert done.result.result == Result.RESULT_OK, done.result.error_message
            after = agent.call(entity, GetEntityState.Request(entity="object")).state.header.stamp
            assert node_suite.ns_of(after) - node_suite.ns_of(before) == 3 * 50_000_000, ns
    finally:
        agent.close()


def episode(env, seed: int, steps: int) -> list[tuple]:
    observation, _ = env.reset(seed=seed)
    trace = [(observation, 0.0)]
    actions = np.random.default_rng(seed).uniform(-1, 1, size=(steps, 8))
    for action in actions:
        observation, reward, *_ = env.step(action)
        trace.append((observation, reward))
    return trace


def assert_same(trace, expected, where: str) -> None:
    assert len(trace) == len(expected), where
    for step, ((obs, reward), (want_obs, want_reward)) in enumerate(zip(trace, expected)):
        assert float_bits(obs) == float_bits(want_obs), f"{where}: observation of step {step}"
        assert float_bits([reward]) == float_bits([want_reward]), f"{where}: reward of step {step}"


def wait_until_back(suite, namespace: str, timeout: float = 20.0) -> None:
    """Until the environment in `namespace` was started again (its sim said it is up a second
    time), with the launcher still running."""
    deadline = time.monotonic() + timeout
    while suite.text().count(f"{namespace}/sim up") < 2:
        assert time.monotonic() < deadline, f"{namespace} did not come back:\n{suite.text()[-3000:]}"
        time.sleep(0.1)
    assert suite.process.poll() is None, "the launcher goes on"


def test_a_failing_node_restarts_its_environment_alone(suite):
    expected = episode(CompoSuiteNativeEnv(TASK), 3, 20)
    with CompoSuiteRosEnv(TASK, NAMESPACES[0]) as env_00:
        assert_same(episode(env_00, 3, 20), expected, "env_00 before the fault")
        agent = RclpyAgent(suite.domain)
        try:
            client = agent.node.create_client(SetParameters, f"{NAMESPACES[1]}/sim/set_parameters")
            value = ParameterValue(type=ParameterType.PARAMETER_BOOL, bool_value=True)
            agent.call(client, SetParameters.Request(parameters=[Parameter(name="fault_panic", value=value)]))
        finally:
            agent.close()
        suite.wait_for_log(f"sim in {NAMESPACES[1]} failed: panicked: fault_panic was set")
        assert f"stopping the other nodes of {NAMESPACES[1]} and starting it again in 0.5 s" \
            " (restart 1 of 2); the other environments go on" in suite.text()
        # While env_01 is down and coming back, env_00 steps on, still bit for bit.
        assert_same(episode(env_00, 3, 20), expected, "env_00 during the restart")
    wait_until_back(suite, NAMESPACES[1])
    # The restarted environment serves episodes again, the same as before.
    with CompoSuiteRosEnv(TASK, NAMESPACES[1], timeout=20.0) as env_01:
        assert_same(episode(env_01, 3, 20), expected, "env_01 after its restart")
    with CompoSuiteRosEnv(TASK, NAMESPACES[2]) as env_02:
        assert_same(episode(env_02, 3, 5), expected[:6], "env_02")


# --processes K: the composed environments split over K child processes, each a container on a
# participant of its own. Same graph and numbers; a process killed outright (what composition
# alone cannot survive) takes only its share down, and launch starts that share again.
SPLIT_NS = "/cmpk"
SPLIT_ENVS = 4
SPLIT_NAMESPACES = [f"{SPLIT_NS}/env_{i:02}" for i in range(SPLIT_ENVS)]


def share_processes(launcher: int) -> dict[str, int]:
    """The launcher's `composuite launch --env-range A..B` children, by range."""
    shares = {}
    for proc in Path("/proc").iterdir():
        if not proc.name.isdigit():
            continue
        try:
            args = (proc / "cmdline").read_bytes().decode(errors="replace").split("\0")
            parent = int((proc / "stat").read_text().rsplit(")", 1)[1].split()[1])
        except (OSError, ValueError, IndexError):
            continue
        if parent == launcher and "--env-range" in args:
            shares[args[args.index("--env-range") + 1]] = int(proc.name)
    return shares


def test_environments_split_over_processes_step_alike_and_a_killed_share_restarts(tmp_path):
    with launch_running(tmp_path, SPLIT_NS, TASK, "--envs", str(SPLIT_ENVS), "--processes", "2",
                        "--respawn", "1", "--respawn-delay", "0.5",
                        service_mapping="fastdds") as suite:
        assert "in 2 processes (one DDS participant each)" in suite.text()
        shares = share_processes(suite.process.pid)
        assert sorted(shares) == ["0..2", "2..4"], shares
        agent = RclpyAgent(suite.domain)
        try:
            wanted = {(node, ns) for ns in SPLIT_NAMESPACES for node in ("sim", "task_manager", "reward")}
            agent.spin_until(lambda: wanted <= set(agent.node.get_node_names_and_namespaces()), 25.0,
                             "the twelve nodes in rclpy's graph")
        finally:
            agent.close()
        expected = episode(CompoSuiteNativeEnv(TASK), 3, 10)
        for ns in SPLIT_NAMESPACES:
            with CompoSuiteRosEnv(TASK, ns) as env:
                assert_same(episode(env, 3, 10), expected, ns)

        os.kill(shares["0..2"], signal.SIGKILL)
        suite.wait_for_log(f"environments 0..2 of {SPLIT_NS} (a process) exited on its own "
                           "(killed by signal 9); starting it again in 0.5 s (restart 1 of 1)")
        # The other share steps on meanwhile, bit for bit.
        with CompoSuiteRosEnv(TASK, SPLIT_NAMESPACES[3]) as env_03:
            assert_same(episode(env_03, 3, 10), expected, "env_03 while 0..2 restarts")
        wait_until_back(suite, SPLIT_NAMESPACES[0])
        with CompoSuiteRosEnv(TASK, SPLIT_NAMESPACES[0], timeout=20.0) as env_00:
            assert_same(episode(env_00, 3, 10), expected, "env_00 after its process restarted")
    assert share_processes(suite.process.pid) == {}, "share processes left running"
