"""The node suite (task_manager_node, sim_node, reward_node) against a raw-DDS agent: the
`cyclonedds` Python package via ros_agent.py, i.e. what an rclpy agent on rmw_cyclonedds puts on
the wire; services in rmw_cyclonedds' format (task_manager `-p service_mapping:=cyclone`).

What is checked:
- discovery: every topic and service of the suite with its ROS type name and QoS (reliability,
  durability; history depth is not announced by RustDDS), and `joint_states` as a driver sends it;
- 500 lockstep steps after set_task + reset: stamps (reward = observation = world_state of the
  same step, +50 ms per step, clock), and every observation bit-identical to the in-process
  reference `env_replay` given the same task, seed and commands (rewards too);
- the scripted expert's commands succeed at the step env_replay says;
- bad input of every kind: refused or clamped with a log line naming what was wrong, the suite
  stays up and the episode goes on exactly as if the bad input had not been sent;
- sample_tasks: the same splits as `composuite tasks --split ... --json` and CPython's `random`.

Every node runs in its own namespace of a random domain, and the module's teardown checks that
each exits 0 within a few seconds of SIGINT. Only run inside scripts/netns-isolate."""

# No `from __future__ import annotations`: cyclonedds resolves annotations at runtime.
import math
import random
import re
import time

import pytest
from cyclonedds.util import duration

import node_suite
import test_splits_reference as splits
from node_suite import Suite, ns_of, env_replay_expert, env_replay_run, float_bits
from ros_agent import Agent

pytestmark = pytest.mark.filterwarnings("error::pytest.PytestUnhandledThreadExceptionWarning")

TASK = "Panda/hollow_box/object_door/shelf"
EXPERT_TASK = "IIWA/box/no_obstacle/pick_place"
DEFAULT_TASK = "IIWA/box/no_obstacle/pick_place"  # task_manager's `task` parameter default
CONTROL_PERIOD_NS = 50_000_000
STEP_TIMEOUT = 5.0
FAR_STEPS = 100  # steps towards a target beyond a joint's limit

JOINT_STATE = "sensor_msgs/msg/JointState"
STATE, LATCHED, CLOCK = ("reliable", "volatile"), ("reliable", "transient_local"), ("best_effort", "volatile")
# topic -> (ROS type, who of the suite has it, reliability/durability)
TOPICS = {
    "joint_states": (JOINT_STATE, "publication", STATE),
    "joint_command": (JOINT_STATE, "subscription", STATE),
    "gripper_command": ("control_msgs/msg/GripperCommand", "subscription", STATE),
    "reference_action": ("std_msgs/msg/Float64MultiArray", "subscription", STATE),
    "reference_action_stamped": ("composuite_msgs/msg/ReferenceAction", "subscription", STATE),
    "observation": ("composuite_msgs/msg/Observation", "publication", STATE),
    "world_state": ("composuite_msgs/msg/WorldState", "publication", STATE),
    "scene": ("composuite_msgs/msg/Scene", "publication", LATCHED),
    "reward": ("composuite_msgs/msg/StagedReward", "publication", STATE),
    "success": ("std_msgs/msg/Bool", "publication", STATE),
    "episode": ("composuite_msgs/msg/EpisodeStatus", "publication", STATE),
    "clock": ("rosgraph_msgs/msg/Clock", "publication", CLOCK),
    "tf": ("tf2_msgs/msg/TFMessage", "publication", STATE),
    "robot_description": ("std_msgs/msg/String", "publication", LATCHED),
    "tf_static": ("tf2_msgs/msg/TFMessage", "publication", LATCHED),
    "scene_markers": ("visualization_msgs/msg/MarkerArray", "publication", LATCHED),
    "object_markers": ("visualization_msgs/msg/MarkerArray", "publication", STATE),
}
SERVICES = {"set_task": "SetTask", "reset": "Reset", "sample_tasks": "SampleTasks"}
FINGERS = ["l_finger_joint", "r_finger_joint"]



# ---- the suite and the agent -------------------------------------------------------------------


@pytest.fixture(scope="module")
def domain() -> int:
    return node_suite.random_domain()


@pytest.fixture(scope="module")
def suite(tmp_path_factory, domain):
    """The main environment, /cy: lockstep, services in the Cyclone format."""
    with node_suite.running(tmp_path_factory.mktemp("cyclone_logs"), "/cy", domain,
                            task_manager={"service_mapping": "cyclone"}) as s:
        yield s


@pytest.fixture(scope="module")
def short_suite(tmp_path_factory, domain):
    """A second environment, /cy_h5, whose episodes last 5 steps (for "step after done")."""
    with node_suite.running(tmp_path_factory.mktemp("cyclone_h5_logs"), "/cy_h5", domain,
                            task_manager={"service_mapping": "cyclone", "horizon": 5}) as s:
        yield s


@pytest.fixture(autouse=True)
def show_logs_on_failure(request):
    """Print the nodes' stderr after every test: pytest shows it only when the test failed."""
    yield
    for name in ("suite", "short_suite"):
        if name in request.fixturenames:
            print(request.getfixturevalue(name).all_stderr())


class Driver:
    """One agent stepping one environment: publishers, subscriptions, service clients, and the
    episode/step it is at."""

    def __init__(self, agent: Agent, suite: Suite):
        self.agent, self.suite = agent, suite
        self.observation = agent.subscribe("observation", "composuite_msgs/msg/Observation")
        self.reward = agent.subscribe("reward", "composuite_msgs/msg/StagedReward")
        self.world_state = agent.subscribe("world_state", "composuite_msgs/msg/WorldState")
        self.status = agent.subscribe("episode", "composuite_msgs/msg/EpisodeStatus")
        self.success = agent.subscribe("success", "std_msgs/msg/Bool")
        self.joint_states = agent.subscribe("joint_states", JOINT_STATE)
        self.clock = agent.subscribe("clock", "rosgraph_msgs/msg/Clock", qos="clock")
        self.command = agent.publisher("joint_command", JOINT_STATE)
        self.gripper = agent.publisher("gripper_command", "control_msgs/msg/GripperCommand")
        self.set_task_client = agent.service_client("set_task", "composuite_msgs/srv/SetTask", "cyclone")
        self.reset_client = agent.service_client("reset", "composuite_msgs/srv/Reset", "cyclone")
        self.sample_client = agent.service_client("sample_tasks", "composuite_msgs/srv/SampleTasks", "cyclone")
        self.episode = self.step_count = None
        self.arm_names: list[str] = []
        self.start_pose: list[float] = []

    def wait_ready(self, timeout: float = 15.0) -> None:
        self.command.wait_for_subscribers(timeout=timeout)
        self.gripper.wait_for_subscribers(timeout=timeout)
        for sub in (self.observation, self.reward, self.world_state, self.status, self.joint_states):
            sub.wait_for_publishers(timeout=timeout)
        for client in (self.set_task_client, self.reset_client, self.sample_client):
            client.wait_for_service(timeout=timeout)

    def warm_up(self, attempts: int = 10) -> None:
        """Reset and step once until every topic the tests read has delivered a sample of it.
        Matching is seen from each side on its own: this agent's reader may list the node's
        writer before that writer lists the reader, and a volatile sample sent in between is
        not for us. Wait until the nodes' writers know this agent too."""
        missing: list[str] = []
        for _ in range(attempts):
            try:
                reply = self.reset_client.call(timeout=10)
            except TimeoutError as error:
                raise AssertionError(f"{error}\n{self.suite.all_stderr()}") from None
            assert reply.success, reply.message
            episode, stamp = reply.episode, reply.observation.header.stamp
            try:
                states = self.joint_states.wait_for({"header.stamp": stamp}, timeout=1.0)
            except TimeoutError:
                missing = ["joint_states"]
                continue
            names = [n for n in states.name if n not in FINGERS]
            successes = len(self.success.samples)
            self.command.publish(name=names, position=list(states.position[:len(names)]))
            want = {"episode": episode, "step": 1}
            missing = []
            for name, sub in (("observation", self.observation), ("world_state", self.world_state),
                              ("reward", self.reward), ("episode", self.status)):
                try:
                    sub.wait_for(want, timeout=1.0)
                except TimeoutError:
                    missing.append(name)
            if len(self.success.samples) == successes:
                missing.append("success")
            if not missing:
                return
        raise AssertionError(f"after {attempts} resets, still nothing on {missing}\n{self.suite.all_stderr()}")

    def set_task(self, task: str):
        robot, obj, obstacle, objective = task.split("/")
        return self.set_task_client.call(robot=robot, object=obj, obstacle=obstacle, objective=objective,
                                         timeout=10)

    def reset(self, seed: int):
        """reset(seed) through the service; the reply's step-0 observation, the arm's joint
        names and pose from the joint_states of the same stamp."""
        reply = self.reset_client.call(seed=seed, use_seed=True, timeout=10)
        assert reply.success, reply.message
        assert reply.seed == seed and reply.observation.episode == reply.episode
        assert reply.observation.step == 0
        self.episode, self.step_count = reply.episode, 0
        states = self.joint_states.wait_for({"header.stamp": reply.observation.header.stamp}, timeout=STEP_TIMEOUT)
        self.arm_names = [n for n in states.name if n not in FINGERS]
        self.start_pose = list(states.position[:len(self.arm_names)])
        return reply

    def step(self, joints, finger: float | None = None, right_finger: float | None = None):
        """One lockstep step: publish joint_command, return (observation, reward, world_state)
        of the next step of this episode."""
        names, positions = list(self.arm_names), list(joints)
        if finger is not None:
            names.append("l_finger_joint"), positions.append(finger)
        if right_finger is not None:
            names.append("r_finger_joint"), positions.append(right_finger)
        start = len(self.observation.samples)
        self.command.publish(name=names, position=positions)
        return self.expect_step(start)

    def expect_step(self, start: int = 0):
        self.step_count += 1
        want = {"episode": self.episode, "step": self.step_count}
        try:
            observation = self.observation.wait_for(want, timeout=STEP_TIMEOUT, start=start)
            reward = self.reward.wait_for(want, timeout=STEP_TIMEOUT)
            world = self.world_state.wait_for(want, timeout=STEP_TIMEOUT)
        except TimeoutError as error:
            raise AssertionError(f"{error}\n{self.suite.all_stderr()}") from None
        return observation, reward, world

    def send_gripper(self, position: float, max_effort: float) -> None:
        """gripper_command, delivered (acknowledged) before the next joint_command goes out: the
        two topics are not ordered with respect to each other."""
        self.gripper.publish(position=position, max_effort=max_effort)
        self.gripper.writer.wait_for_acks(duration(seconds=2))

    def raw_command(self, names, positions) -> None:
        self.command.publish(name=list(names), position=list(positions))

    def assert_no_new_step(self, wait: float = 0.3) -> None:
        """No observation beyond the current step of this episode arrives within `wait` s."""
        time.sleep(wait)
        extra = [(o.episode, o.step) for o in self.observation.samples
                 if o.episode == self.episode and o.step > self.step_count]
        assert not extra, f"observations of steps that should not exist: {extra}"


@pytest.fixture(scope="module")
def driver(suite, domain):
    with Agent(namespace=suite.namespace, domain_id=domain) as agent:
        d = Driver(agent, suite)
        d.wait_ready()
        d.warm_up()
        yield d
        # Nothing the agent was sent made a node fall over.
        suite.assert_running()


@pytest.fixture(scope="module")
def short_driver(short_suite, domain):
    with Agent(namespace=short_suite.namespace, domain_id=domain) as agent:
        d = Driver(agent, short_suite)
        d.wait_ready()
        d.warm_up()
        yield d
        short_suite.assert_running()


def random_walk(rng: random.Random, start: list[float], steps: int, size: float = 0.04,
                reach: float = 0.4) -> list[list[float]]:
    """Reproducible arm targets near the start pose: a bounded random walk, each value rounded
    to 6 decimals so that it parses to the same double in Python and in env_replay's JSON."""
    q, out = list(start), []
    for _ in range(steps):
        q = [min(max(v + rng.uniform(-size, size), s - reach), s + reach) for v, s in zip(q, start)]
        out.append([round(v, 6) for v in q])
    return out


def compare_with_replay(task: str, seed: int, commands: list[dict], observations: list, rewards: list,
                        horizon: int | None = None) -> list[dict]:
    """env_replay on the same task, seed and commands: every observation's `flat` bit for bit,
    every reward's total bit for bit and its success flag. `observations[0]` is step 0."""
    episode = {"task": task, "seed": seed, "commands": commands}
    if horizon is not None:
        episode["horizon"] = horizon
    replay = env_replay_run(episode)
    assert len(replay) == len(observations), (len(replay), len(observations))
    bad_obs = [o.step for o, r in zip(observations, replay) if float_bits(o.flat) != float_bits(r["flat"])]
    assert not bad_obs, f"observations differing from env_replay at steps {bad_obs[:10]} (of {len(bad_obs)})"
    bad_rewards = [(w.step, w.total, r["reward"], w.success, r["success"])
                   for w, r in zip(rewards, replay[1:])
                   if float_bits([w.total]) != float_bits([r["reward"]]) or w.success != r["success"]]
    assert not bad_rewards, f"rewards differing from env_replay (step, ours, reference...): {bad_rewards[:10]}"
    return replay


# ---- discovery --------------------------------------------------------------------------------


def test_discovery_types_and_qos_and_joint_states(driver, suite):
    ns = suite.namespace
    wanted = {(f"rt{ns}/{topic}", kind) for topic, (_, kind, _) in TOPICS.items()}
    wanted |= {(f"rq{ns}/{name}Request", "subscription") for name in SERVICES}
    wanted |= {(f"rr{ns}/{name}Reply", "publication") for name in SERVICES}

    def complete() -> bool:
        seen = {(e.topic_name, e.kind) for e in driver.agent.discovered_topics()}
        return wanted <= seen

    deadline = time.monotonic() + 10
    while not complete() and time.monotonic() < deadline:
        time.sleep(0.05)
    endpoints = [e for e in driver.agent.discovered_topics() if e.ros_name.startswith(ns + "/")]
    seen = {(e.topic_name, e.kind) for e in endpoints}
    assert wanted <= seen, f"not discovered: {sorted(wanted - seen)}"

    wrong = []
    for e in endpoints:
        kind, name = e.ros_kind, e.ros_name[len(ns) + 1:]
        if kind == "topic" and name in TOPICS:
            ros_type, _, (reliability, durability) = TOPICS[name]
        elif kind in ("service_request", "service_reply") and name in SERVICES:
            half = "Request" if kind == "service_request" else "Response"
            ros_type, reliability, durability = f"composuite_msgs/srv/{SERVICES[name]}_{half}", *STATE
        else:
            continue  # parameter services, rosout, ... are tested elsewhere
        if (e.ros_type, e.reliability, e.durability) != (ros_type, reliability, durability):
            wrong.append((e.topic_name, e.kind, e.ros_type, e.reliability, e.durability))
    assert not wrong, f"endpoints with the wrong type or QoS: {wrong}"

    # joint_states as a real arm's driver publishes it: 7 arm joints + the two fingers.
    reply = driver.reset(seed=1)
    states = driver.joint_states.wait_for({"header.stamp": reply.observation.header.stamp})
    assert list(states.name) == [f"joint_{i}" for i in range(1, 8)] + FINGERS
    assert len(states.position) == len(states.velocity) == 9
    assert all(math.isfinite(v) for v in [*states.position, *states.velocity])
    assert states.position[7] == pytest.approx(-states.position[8], abs=1e-6)  # coupled fingers
    # The latched topics reach a late joiner (this subscription is made long after they were sent).
    description = driver.agent.subscribe("robot_description", "std_msgs/msg/String", qos="latched")
    urdf = description.wait_for(timeout=STEP_TIMEOUT).data
    assert "<robot" in urdf and all(f'name="{n}"' in urdf for n in states.name)
    scene = driver.agent.subscribe("scene", "composuite_msgs/msg/Scene", qos="latched")
    assert scene.wait_for({"episode": reply.episode}, timeout=STEP_TIMEOUT).seed == 1


# ---- 500 lockstep steps, bit-identical to the in-process Env -----------------------------------


def test_500_lockstep_steps_bit_identical_to_env_replay(driver):
    answer = driver.set_task(TASK)
    assert answer.success, answer.message
    assert (answer.task.robot, answer.task.object, answer.task.obstacle, answer.task.objective) == tuple(
        TASK.split("/"))
    seed = 11
    reply = driver.reset(seed)
    assert len(reply.observation.flat) == 93
    # The reset state's reward: its stages, stamped like the step-0 observation, but it earns 0.
    start = driver.reward.wait_for({"episode": driver.episode, "step": 0}, timeout=STEP_TIMEOUT)
    assert ns_of(start.header.stamp) == ns_of(reply.observation.header.stamp)
    assert start.total == 0.0 and not start.success and len(start.stage_values) == 5
    assert max(start.stage_values) > 0, "the gripper starts some way from the object: reach > 0"
    rng = random.Random(20261122)
    targets = random_walk(rng, driver.start_pose, 500)
    # Gripper changes: through gripper_command, and as finger joints inside joint_command.
    gripper_at = {60: (0.02, 0.0), 200: (0.07, 15.0), 350: (0.0, 40.0)}
    finger_at = {120: ("l", 0.005), 280: ("r", -0.012), 430: ("l", 0.02)}
    commands, observations, rewards, worlds = [], [reply.observation], [], []
    for k, joints in enumerate(targets, start=1):
        command = {"joints": joints, "gripper": None}
        finger = right = None
        if k in gripper_at:
            driver.send_gripper(*gripper_at[k])
            command["gripper"] = list(gripper_at[k])
        if k in finger_at:
            side, value = finger_at[k]
            finger, right = (value, None) if side == "l" else (None, value)
            command["finger"] = value if side == "l" else -value
        observation, reward, world = driver.step(joints, finger, right)
        commands.append(command)
        observations.append(observation)
        rewards.append(reward)
        worlds.append(world)

    stamps = [ns_of(o.header.stamp) for o in observations]
    assert [b - a for a, b in zip(stamps, stamps[1:])] == [CONTROL_PERIOD_NS] * 500
    assert [ns_of(r.header.stamp) for r in rewards] == stamps[1:]
    assert [ns_of(w.header.stamp) for w in worlds] == stamps[1:]
    # /clock carries the same sim time (best effort: a lost sample is allowed, a wrong one not).
    clocks = [ns_of(c.clock) for c in driver.clock.samples if stamps[0] <= ns_of(c.clock) <= stamps[-1]]
    assert clocks == sorted(set(clocks)) and set(clocks) <= set(stamps)
    assert len(clocks) >= 0.9 * len(stamps), (len(clocks), len(stamps))
    # The episode status follows every step; the horizon (500) ends it.
    status = driver.status.wait_for({"episode": driver.episode, "step": 500}, timeout=STEP_TIMEOUT)
    assert status.done and status.truncated and not status.terminated and status.seed == seed
    assert ns_of(status.header.stamp) == stamps[-1]
    # ... and announces the episode's start: step 0, with the reset's stamp, running, return 0.
    statuses = [s for s in driver.status.samples if s.episode == driver.episode]
    assert [s.step for s in statuses] == list(range(0, 501))
    start = statuses[0]
    assert ns_of(start.header.stamp) == stamps[0] and not start.done and start.episode_return == 0.0
    replay = compare_with_replay(TASK, seed, commands, observations, rewards)
    assert replay[-1]["truncated"]
    assert status.episode_return == pytest.approx(sum(r["reward"] for r in replay[1:]), rel=1e-12)
    # The commands did move the fingers (the gripper changes were applied, not dropped).
    gripper_qpos = {round(o.robot.gripper_qpos[0], 3) for o in observations}
    assert len(gripper_qpos) > 3


# ---- a successful episode ----------------------------------------------------------------------


def test_expert_commands_succeed_at_the_reference_step(driver):
    expert = env_replay_expert(EXPERT_TASK, 0)
    assert expert["success_step"] is not None
    # gripper_command only when the expert's gripper action changes (the sim holds it otherwise).
    commands, previous = [], None
    for c in expert["commands"][:expert["success_step"]]:
        gripper = c["gripper"] if c["gripper"] != previous else None
        previous = c["gripper"] if c["gripper"] is not None else previous
        commands.append({"joints": c["joints"], "gripper": gripper})
    replay = env_replay_run({"task": EXPERT_TASK, "seed": 0, "commands": commands})
    reference_success = next(r["step"] for r in replay if r["success"])
    assert reference_success == expert["success_step"]

    assert driver.set_task(EXPERT_TASK).success
    driver.reset(0)
    successes_before = len(driver.success.samples)
    rewards = []
    for command in commands:
        if command["gripper"] is not None:
            driver.send_gripper(*command["gripper"])
        _, reward, _ = driver.step(command["joints"])
        rewards.append(reward)
    first_success = next((r.step for r in rewards if r.success), None)
    assert first_success == reference_success
    # `success` (std_msgs/Bool, one per step) says it too, and never before that step.
    driver.success.wait_for(lambda s: s.data, timeout=STEP_TIMEOUT, start=successes_before)
    flags = [s.data for s in driver.success.samples[successes_before:]]
    assert flags.index(True) == first_success - 1, flags
    status = driver.status.wait_for({"episode": driver.episode, "step": first_success})
    assert status.success_seen and not status.done


# ---- bad input ---------------------------------------------------------------------------------


def test_bad_input_is_refused_and_the_episode_goes_on(driver, suite):
    assert driver.set_task(TASK).success
    seed = 5
    reply = driver.reset(seed)
    rng = random.Random(5)
    names = driver.arm_names
    good = random_walk(rng, driver.start_pose, 80, size=0.02)
    commands, observations, rewards = [], [reply.observation], []

    def good_step(joints, **extra):
        observation, reward, _ = driver.step(joints)
        commands.append({"joints": joints, "gripper": None, **extra})
        observations.append(observation)
        rewards.append(reward)

    def refused(node: str, send, *words: str) -> str:
        """Send something bad, then a good step; the bad thing must not have stepped, and the
        node's log must name it (every word in `words`)."""
        before = len(suite.stderr(node))
        send()
        driver.assert_no_new_step(wait=0.05)
        good_step(good[len(commands)])
        log = suite.wait_for_log(node, words[0], timeout=2.0, since=before)
        assert "[WARN]" in log and all(w in log for w in words), (words, log)
        return log

    good_step(good[0])
    arm = list(good[0])
    nan_at_2 = arm[:1] + [math.nan] + arm[2:]
    refused("sim", lambda: driver.raw_command(names, nan_at_2), "joint_command refused", "NaN", "finite")
    refused("sim", lambda: driver.raw_command(names, arm[:6] + [math.inf]),
            "joint_command refused", "inf", "finite")
    refused("sim", lambda: driver.raw_command(names + ["l_finger_joint"], arm + [-math.inf]),
            "joint_command refused", "-inf")
    refused("sim", lambda: driver.raw_command(names, arm[:6]),
            "joint_command refused", "7 names but 6 positions")
    refused("sim", lambda: driver.raw_command(names[:6] + ["joint_9"], arm),
            "joint_command refused", "unknown joint `joint_9`", names[0], "l_finger_joint")
    refused("sim", lambda: driver.raw_command(names[:6], arm[:6]),
            "joint_command refused", "missing", names[6])
    refused("sim", lambda: driver.raw_command(names + names[:1], arm + arm[:1]),
            "joint_command refused", f"`{names[0]}` twice")
    refused("sim", lambda: driver.raw_command([], []), "joint_command refused", "missing")
    refused("sim", lambda: driver.send_gripper(math.nan, 0.0), "gripper_command refused", "position is NaN")
    refused("sim", lambda: driver.send_gripper(0.05, -1.0), "gripper_command refused", "max_effort is -1")
    refused("sim", lambda: driver.send_gripper(0.05, math.inf), "gripper_command refused", "max_effort is inf")

    # An unknown task: refused with the valid choices; the running episode is untouched.
    task_log_start = len(suite.stderr("task_manager"))
    bad_task = driver.set_task_client.call(robot="UR5", object="box", obstacle="no_obstacle",
                                           objective="pick_place", timeout=10)
    assert not bad_task.success
    assert "UR5" in bad_task.message and all(r in bad_task.message for r in ("IIWA", "Jaco", "Panda"))
    bad_task = driver.set_task_client.call(robot="IIWA", object="sphere", obstacle="no_obstacle",
                                           objective="pick_place", timeout=10)
    assert not bad_task.success
    assert "sphere" in bad_task.message and all(o in bad_task.message for o in ("box", "dumbbell", "plate"))
    # A seed out of range: refused, says the range; nothing restarts.
    bad_reset = driver.reset_client.call(seed=2**32, use_seed=True, timeout=10)
    assert not bad_reset.success
    assert "4294967296" in bad_reset.message and "4294967295" in bad_reset.message
    log = suite.wait_for_log("task_manager", "sphere", since=task_log_start)
    assert log.count("set_task refused") == 2 and "UR5" in log, log
    driver.assert_no_new_step(wait=0.05)
    for _ in range(5):
        good_step(good[len(commands)])

    # Targets beyond the limits are clamped (said once), the joint stays within them.
    before = len(suite.stderr("sim"))
    resume = len(commands)
    far = list(good[resume - 1])
    far[6] = 10.0  # the wrist turns towards +10 rad, far beyond its limit
    for _ in range(FAR_STEPS):
        good_step(far)
    log = suite.wait_for_log("sim", "target clamped", since=before)
    clamp_lines = [line for line in log.splitlines() if "clamped" in line]
    assert len(clamp_lines) == 1 and f"`{names[6]}`" in clamp_lines[0], log
    lower, upper = map(float, re.search(r"limits \[(\S+), (\S+)\]", clamp_lines[0]).groups())
    angles = [math.atan2(o.robot.joint_pos_sin[6], o.robot.joint_pos_cos[6]) for o in observations[-FAR_STEPS:]]
    assert all(lower - 1e-3 <= a <= upper + 1e-3 for a in angles), (lower, upper, angles[-5:])
    # It went all the way to the limit and stays there (unclamped, it would pass pi and wrap).
    assert all(abs(a - upper) < 0.02 for a in angles[-10:]), (upper, angles[::10], angles[-5:])
    states = driver.joint_states.wait_for({"header.stamp": observations[-1].header.stamp})
    assert states.position[6] <= upper + 1e-3

    for i in range(5):
        good_step(good[resume + i])
    suite.assert_running()
    # The episode is exactly the one of the good commands alone.
    assert [o.step for o in observations] == list(range(len(observations)))
    compare_with_replay(TASK, seed, commands, observations, rewards)


def test_step_after_done_is_refused_once_and_reset_recovers(short_driver, short_suite):
    d = short_driver
    seed = 4
    reply = d.reset(seed)
    rng = random.Random(4)
    targets = random_walk(rng, d.start_pose, 7)
    observations, rewards = [reply.observation], []
    for joints in targets[:5]:
        observation, reward, _ = d.step(joints)
        observations.append(observation)
        rewards.append(reward)
    status = d.status.wait_for({"episode": d.episode, "step": 5})
    assert status.done and status.truncated and status.reason == 1  # REASON_HORIZON
    before = len(short_suite.stderr("sim"))
    for joints in targets[5:]:  # the 6th and 7th command: the episode is over
        d.raw_command(d.arm_names, joints)
    short_suite.wait_for_log("sim", "is over", timeout=2.0, since=before)
    time.sleep(0.3)  # time for a second (wrong) "is over" line
    log = short_suite.stderr("sim")[before:]
    over = [line for line in log.splitlines() if "is over" in line]
    assert len(over) == 1 and "[WARN]" in over[0] and "reset" in over[0], log
    d.assert_no_new_step(wait=0.0)
    commands = [{"joints": j, "gripper": None} for j in targets[:5]]
    compare_with_replay(DEFAULT_TASK, seed, commands, observations, rewards, horizon=5)
    # A reset starts a fresh episode that steps normally.
    reply = d.reset(seed + 1)
    observation, _, _ = d.step(random_walk(rng, d.start_pose, 1)[0])
    assert observation.step == 1 and observation.episode == reply.episode
    short_suite.assert_running()


# ---- sample_tasks ------------------------------------------------------------------------------


@pytest.mark.parametrize("experiment,num_train,element,seed", [
    ("default", 56, "", 3),
    ("smallscale", 20, "Panda", 1),
    ("holdout", 40, "goal_wall", 7),
])
def test_sample_tasks_equals_the_cli_and_the_reference(driver, experiment, num_train, element, seed):
    answer = driver.sample_client.call(experiment=experiment, num_train=num_train, element=element,
                                       seed=seed, no_shuffle=False, timeout=10)
    assert answer.success, answer.message

    def names(specs):
        return [f"{t.robot}/{t.object}/{t.obstacle}/{t.objective}" for t in specs]

    got = {"train": names(answer.train), "test": names(answer.test)}
    assert got == splits.composuite_split(experiment, num_train, element or None, seed)
    reference_element = {"goal_wall": "GoalWall"}.get(element, element) or None
    train, test = splits.reference_split(experiment, num_train, reference_element, seed)
    assert got == {"train": [splits.wire(t) for t in train], "test": [splits.wire(t) for t in test]}


def test_sample_tasks_bad_requests_say_what_is_valid(driver):
    answer = driver.sample_client.call(experiment="smallscale", num_train=10, element="", seed=0, timeout=10)
    assert not answer.success and "element" in answer.message and "IIWA" in answer.message
    assert answer.train == [] and answer.test == []
    answer = driver.sample_client.call(experiment="bogus", num_train=10, seed=0, timeout=10)
    assert not answer.success
    assert "bogus" in answer.message and all(e in answer.message for e in ("default", "smallscale", "holdout"))
    answer = driver.sample_client.call(experiment="default", num_train=1000, seed=0, timeout=10)
    assert not answer.success and "1000" in answer.message
