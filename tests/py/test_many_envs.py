"""`composuite launch --envs 4` driven by a vector of agents, one per environment, stepping all four
at once: each environment follows exactly its own agent (its task, its seed, its commands, bit
for bit as the in-process reference `env_replay`), and nothing of one namespace reaches another.

On one host this runs inside scripts/netns-isolate like every DDS test; test_two_hosts.py runs it
again with the suite on another "host" of scripts/netns-pair (COMPOSUITE_SUITE_NETNS)."""

# No `from __future__ import annotations`: cyclonedds resolves annotations at runtime.
import os
import random
import signal
import subprocess
import threading
import time

import pytest

import node_suite
from node_suite import env_replay_run, float_bits
from ros_agent import Agent, LockstepClient

ENVS = 4
NAMESPACE = "/many"
# Two objectives of different termination rules and two robots, one task per environment.
TASKS = ["IIWA/box/no_obstacle/pick_place", "Panda/plate/object_wall/push",
         "Gen3/dumbbell/goal_wall/trash_can", "Jaco/hollow_box/object_door/shelf"]
ROBOTS = ["IIWA", "Jaco", "Panda", "Gen3"]  # the order of the robot one-hot (TaskFactor.msg)
STEPS = 60
STEP_TIMEOUT = 10.0


def composuite() -> str:
    path = node_suite.node_dir() / "composuite"
    if not path.is_file():
        raise FileNotFoundError(f"{path} not found: build with `cargo build -p composuite`")
    return str(path)


@pytest.fixture(scope="module")
def launched(tmp_path_factory):
    domain = node_suite.random_domain()
    log = tmp_path_factory.mktemp("many_envs") / "launch.stderr"
    env = {k: v for k, v in os.environ.items() if not k.startswith("ROS_")}
    env["ROS_DOMAIN_ID"] = str(domain)
    with open(log, "wb") as stderr:
        process = subprocess.Popen(
            [*node_suite.suite_launcher(), composuite(), "launch", "--envs", str(ENVS),
             "--namespace", NAMESPACE, "--service-mapping", "cyclone", "--log-level", "warn"],
            env=env, stdin=subprocess.DEVNULL, stdout=stderr, stderr=stderr)
    yield domain, process, log
    process.send_signal(signal.SIGINT)
    try:
        code = process.wait(timeout=15)
    except subprocess.TimeoutExpired:
        process.kill()
        code = process.wait()
    assert code == 0, f"launch exited {code}:\n{log.read_text(errors='replace')[-3000:]}"


class EnvAgent(LockstepClient):
    """One agent of the vector: its own participant in its environment's namespace."""

    def __init__(self, index: int, domain: int):
        self.index, self.task, self.seed = index, TASKS[index], 100 + index
        self.namespace = f"{NAMESPACE}/env_{index:02d}"
        super().__init__(Agent(namespace=self.namespace, domain_id=domain))
        self.set_task = self.agent.service_client("set_task", "composuite_msgs/srv/SetTask")
        self.error: BaseException | None = None
        self.commands: list[dict] = []
        self.stepped: list = []

    def run(self, start: threading.Barrier) -> None:
        try:
            for client in (self.set_task, self.reset_client):
                client.wait_for_service(timeout=30)
            self.command.wait_for_subscribers(timeout=30)
            # Matched both ways before the first step: a volatile reward published before its
            # writer knew this reader is not delivered (seen in CI under load).
            for topic in (self.observations, self.rewards, self.states):
                topic.wait_for_publishers(timeout=30)
            time.sleep(0.5)
            robot, obj, obstacle, objective = self.task.split("/")
            answer = self.set_task.call(robot=robot, object=obj, obstacle=obstacle, objective=objective,
                                        timeout=10)
            assert answer.success, answer.message
            self.stepped = [self.reset(seed=self.seed).observation]
            rng = random.Random(self.index)
            start.wait(timeout=60)  # all four step at the same time
            for _ in range(STEPS):
                targets = [round(q + rng.uniform(-0.2, 0.2), 6) for q in self.home]
                self.stepped.append(self.step(targets, timeout=STEP_TIMEOUT))
                self.commands.append({"joints": targets, "gripper": None})
        except BaseException as error:  # reported by the test thread
            self.error = error
            start.abort()


def test_four_environments_step_concurrently_each_following_only_its_agent(launched):
    domain, process, log = launched
    agents = [EnvAgent(i, domain) for i in range(ENVS)]
    try:
        start = threading.Barrier(ENVS)
        threads = [threading.Thread(target=a.run, args=(start,)) for a in agents]
        for thread in threads:
            thread.start()
        for thread in threads:
            thread.join(timeout=300)
        assert process.poll() is None, f"launch died:\n{log.read_text(errors='replace')[-3000:]}"
        errors = {a.namespace: repr(a.error) for a in agents if a.error}
        assert not errors, f"{errors}\n{log.read_text(errors='replace')[-3000:]}"
        for a in agents:
            # No crosstalk: every observation this namespace published belongs to this agent's
            # episodes, one per step, each equal to the in-process run of this agent's commands.
            mine = [(o.episode, o.step) for o in a.observations.samples if o.episode == a.episode and o.step > 0]
            assert sorted(mine) == [(a.episode, k) for k in range(1, STEPS + 1)], a.namespace
            robot_hot = [0.0] * 4
            robot_hot[ROBOTS.index(a.task.split("/")[0])] = 1.0
            assert all(list(o.task.robot_id) == robot_hot for o in a.stepped), a.namespace
            replay = env_replay_run({"task": a.task, "seed": a.seed, "commands": a.commands})
            assert [float_bits(o.flat) for o in a.stepped] == [float_bits(r["flat"]) for r in replay], \
                f"{a.namespace} ({a.task}) differs from env_replay"
        # Different tasks really were running side by side (their observations differ).
        assert len({tuple(float_bits(a.stepped[1].flat)) for a in agents}) == ENVS
    finally:
        for a in agents:
            a.agent.close()
