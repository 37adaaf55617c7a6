"""`composuite launch`, the params files and the `ros2 launch` file.

The launcher is driven as a user would (a subprocess, signals), and watched with the cyclonedds
agent over real DDS, inside the loopback-only namespace the test command provides. (No
`from __future__ import annotations` here: cyclonedds IDL classes need real annotation objects.)"""

import ast
import os
import re
import signal
import subprocess
import time
from pathlib import Path

import pytest
import yaml

import node_suite
import ros_agent

REPO = Path(__file__).resolve().parents[2]


def bin_dir() -> Path:
    return node_suite.node_dir()


def composuite() -> str:
    exe = bin_dir() / "composuite"
    if not exe.is_file():
        raise FileNotFoundError(f"{exe} not found: build with `cargo build -p composuite`")
    return str(exe)


def launch(*args: str, domain: int) -> subprocess.Popen:
    env = dict(os.environ, ROS_DOMAIN_ID=str(domain))
    return subprocess.Popen([composuite(), "launch", *args], env=env,
                            stderr=subprocess.PIPE, text=True)


def test_two_realtime_environments_run_and_stop_cleanly_on_sigterm():
    # --isolate: each node a process of its own (the composed default: test_composed.py).
    domain = node_suite.random_domain()
    suite = launch("--envs", "2", "--isolate", "--namespace", "/lt", "--params-file",
                   str(REPO / "params/realtime.yaml"), "--log-level", "warn", domain=domain)
    try:
        with ros_agent.Agent(namespace="/lt/env_01", domain_id=domain) as agent:
            states = agent.subscribe("joint_states", "sensor_msgs/msg/JointState")
            clock = agent.subscribe("clock", "rosgraph_msgs/msg/Clock", qos="clock")
            states.wait_for_publishers(timeout=20)
            first = states.wait_for(None, timeout=20)
            t0 = time.monotonic()
            time.sleep(1.0)
            later = [s for s in states.samples if s is not first]
            rate = len(later) / (time.monotonic() - t0)
            # Realtime mode: 20 Hz control steps on the wall clock, the last targets held.
            assert 10 <= rate <= 30, f"joint_states at {rate:.1f} Hz"
            stamps = [c.clock.sec + c.clock.nanosec * 1e-9 for c in clock.samples]
            assert stamps == sorted(stamps) and stamps[-1] > stamps[0]
            topics = {e.ros_name for e in agent.discovered_topics() if e.kind == "publication"}
            for ns in ("/lt/env_00", "/lt/env_01"):
                for topic in ("joint_states", "observation", "reward", "episode", "scene"):
                    assert f"{ns}/{topic}" in topics, sorted(topics)
        assert len(node_suite.node_processes("__ns:=/lt/env_0")) == 6
    finally:
        suite.send_signal(signal.SIGTERM)
        _, err = suite.communicate(timeout=15)
    assert suite.returncode == 0, err
    assert "signal 15" in err
    assert node_suite.node_processes("__ns:=/lt/env_0") == [], "nodes left running"


def test_a_dying_node_stops_the_suite_with_an_error_without_respawn():
    domain = node_suite.random_domain()
    suite = launch("--namespace", "/die", "--respawn", "0", "--log-level", "warn", domain=domain)
    try:
        deadline = time.monotonic() + 20
        while len(node_suite.node_processes("__ns:=/die")) < 3:
            assert time.monotonic() < deadline, "the three nodes did not start"
            time.sleep(0.1)
        (sim,) = node_suite.node_processes("__ns:=/die", "sim")
        os.kill(sim, signal.SIGKILL)
        _, err = suite.communicate(timeout=15)
    finally:
        if suite.poll() is None:
            suite.kill()
    assert suite.returncode != 0
    assert "sim in /die exited on its own (killed by signal 9)" in err, err
    assert node_suite.node_processes("__ns:=/die") == []


def test_a_node_is_started_again_up_to_the_respawn_limit_then_the_suite_stops():
    domain = node_suite.random_domain()
    suite = launch("--namespace", "/again", "--respawn", "1", "--respawn-delay", "0.2", "--log-level", "warn",
                   domain=domain)

    def the_sim() -> int:
        deadline = time.monotonic() + 20
        while True:
            pids = node_suite.node_processes("__ns:=/again", "sim")
            if pids:
                return pids[0]
            assert time.monotonic() < deadline and suite.poll() is None, "no sim running"
            time.sleep(0.05)

    try:
        first = the_sim()
        os.kill(first, signal.SIGKILL)
        deadline = time.monotonic() + 20
        while (second := the_sim()) == first:
            assert time.monotonic() < deadline, "the sim was not started again"
            time.sleep(0.05)
        os.kill(second, signal.SIGKILL)  # one death more than --respawn 1 allows
        _, err = suite.communicate(timeout=20)
    finally:
        if suite.poll() is None:
            suite.kill()
    assert "sim in /again exited on its own (killed by signal 9); starting it again in 0.2 s (restart 1 of 1)" in err
    assert "after 1 restart(s) (--respawn 1); stopped the others" in err, err
    assert suite.returncode != 0
    assert node_suite.node_processes("__ns:=/again") == []


def test_bad_launch_options_are_refused_with_the_valid_choices():
    for args, expected in [
        (["--task", "IIWA/box/no_obstacle/fly"], "valid: pick_place, push, trash_can, shelf"),
        (["--mode", "fast"], "valid: lockstep, realtime"),
        (["--service-mapping", "zenoh"], "valid: fastdds"),
        (["--namespace", "env"], "must be absolute"),
        (["--envs", "0"], "valid: 1 to 100"),
        (["--respawn-delay", "nan"], "--respawn-delay NaN is invalid; seconds >= 0"),
    ]:
        result = subprocess.run([composuite(), "launch", *args], capture_output=True, text=True, timeout=20)
        assert result.returncode == 2, (args, result.stderr)
        assert expected in result.stderr, (args, result.stderr)


def node_defaults(binary: str) -> dict[str, str]:
    """Parameter defaults as the node's --help prints them: `  name  description (default)`."""
    text = subprocess.run([str(bin_dir() / binary), "--help"], capture_output=True, text=True,
                          check=True).stdout
    section = text.split("Parameters (default):")[1].split("Example:")[0]
    return {m.group(1): m.group(2) for m in re.finditer(r"^  (\w+) .*\((.*)\)$", section, re.M)}


@pytest.mark.parametrize("args", [
    ["tasks"], ["tasks", "--json"], ["tasks", "--split", "default", "--num-train", "56", "--seed", "0"],
    ["--help"], ["expert", "--help"], ["bench", "--tasks", "IIWA/box/no_obstacle/pick_place", "--steps", "10"],
])
def test_a_closed_stdout_ends_any_subcommand_quietly(args):
    """`composuite tasks | head -1`: the reader is gone before (or while) the command writes. The
    command ends by SIGPIPE as a Unix filter does: no panic, no backtrace, nothing on stderr."""
    read_end, write_end = os.pipe()
    os.close(read_end)  # the reader has already gone: the first write meets a closed pipe
    process = subprocess.Popen([composuite(), *args], stdout=write_end, stderr=subprocess.PIPE)
    os.close(write_end)
    _, err = process.communicate(timeout=120)
    assert err == b"", err.decode(errors="replace")
    assert process.returncode == -signal.SIGPIPE, process.returncode


def test_params_file_holds_every_parameter_at_its_default():
    params = yaml.safe_load((REPO / "params/composuite.yaml").read_text())
    for node in ("sim", "task_manager", "reward"):
        declared = node_defaults(f"{node}_node")
        in_file = dict(params["/**"]["ros__parameters"])
        in_file.update(params.get(f"/**/{node}", {}).get("ros__parameters", {}))
        assert set(in_file) == set(declared), node
        for name, value in in_file.items():
            if isinstance(value, bool):
                shown = str(value).lower()
            elif isinstance(value, list):  # a YAML flow list, as --help shows arrays
                shown = "[" + ", ".join(str(v) for v in value) + "]"
            else:
                shown = str(value)
            assert shown == declared[name], (node, name, value, declared[name])


def test_ros2_launch_file_names_real_parameters_with_the_same_defaults():
    source = (REPO / "launch_scripts/composuite.launch.py").read_text()
    tree = ast.parse(source)
    constants = {t.id: ast.literal_eval(node.value) for node in tree.body
                 if isinstance(node, ast.Assign) for t in node.targets
                 if isinstance(t, ast.Name) and t.id in ("ARGUMENTS", "NODE_PARAMETERS")}
    defaults = {name: default for name, default, _ in constants["ARGUMENTS"]}
    for node, parameters in constants["NODE_PARAMETERS"].items():
        declared = node_defaults(f"{node}_node")
        for p in parameters:
            assert p in declared, (node, p)
            assert defaults[p] == declared[p], (node, p, defaults[p], declared[p])


@pytest.mark.parametrize("binary", ["sim_node", "task_manager_node", "reward_node"])
def test_node_help_and_bad_arguments(binary):
    help_text = subprocess.run([str(bin_dir() / binary), "--help"], capture_output=True, text=True)
    assert help_text.returncode == 0 and "--ros-args" in help_text.stdout
    bad = subprocess.run([str(bin_dir() / binary), "--ros-args", "-r", "__ns:=relative"],
                         capture_output=True, text=True, timeout=20)
    assert bad.returncode == 2 and "must be absolute" in bad.stderr


def test_ros_domain_id_is_honoured_and_checked():
    domain = node_suite.random_domain()
    env = dict(os.environ, ROS_DOMAIN_ID=str(domain), ROS_AUTOMATIC_DISCOVERY_RANGE="LOCALHOST")
    node = subprocess.Popen([str(bin_dir() / "reward_node"), "--ros-args", "-r", "__ns:=/dom"],
                            env=env, stderr=subprocess.PIPE, text=True)
    try:
        def publishes_reward(e):
            return e.kind == "publication" and e.ros_name == "/dom/reward"
        with ros_agent.Agent(domain_id=domain) as same:
            same.wait_for_endpoint(publishes_reward, timeout=10)
        with ros_agent.Agent(domain_id=node_suite.other_domain(domain)) as other:
            time.sleep(1.5)
            assert not any(publishes_reward(e) for e in other.discovered_topics())
    finally:
        node.send_signal(signal.SIGINT)
        _, err = node.communicate(timeout=10)
    assert node.returncode == 0, err
    bad = subprocess.run([str(bin_dir() / "sim_node")], env=dict(os.environ, ROS_DOMAIN_ID="300"),
                         capture_output=True, text=True, timeout=20)
    assert bad.returncode == 2 and "ROS_DOMAIN_ID=300 is invalid; valid: 0..=232" in bad.stderr


def test_remaps_and_node_name_apply_to_a_running_node():
    domain = node_suite.random_domain()
    env = dict(os.environ, ROS_DOMAIN_ID=str(domain))
    node = subprocess.Popen([str(bin_dir() / "sim_node"), "--ros-args", "-r", "__ns:=/rm",
                             "-r", "__node:=arm_sim", "-r", "joint_states:=arm_states",
                             "-r", "joint_command:=/global_command"],
                            env=env, stderr=subprocess.PIPE, text=True)
    try:
        with ros_agent.Agent(domain_id=domain) as agent:
            agent.wait_for_endpoint(lambda e: e.kind == "publication" and e.ros_name == "/rm/arm_states",
                                    timeout=10)
            agent.wait_for_endpoint(lambda e: e.kind == "subscription" and e.ros_name == "/global_command",
                                    timeout=10)
            agent.wait_for_endpoint(lambda e: e.ros_name == "/rm/arm_sim/get_parameters", timeout=10)
            names = {e.ros_name for e in agent.discovered_topics()}
            assert "/rm/joint_states" not in names and "/rm/joint_command" not in names
    finally:
        node.send_signal(signal.SIGINT)
        _, err = node.communicate(timeout=10)
    assert node.returncode == 0, err
    assert "[rm.arm_sim]" in err


class BareNodes:
    """Node binaries started on their own (no launcher) in `namespace` of a fresh random domain,
    with the given ROS arguments (and `per_node[kind]` for that kind only); on exit they get
    SIGINT, and `errs` holds each one's stderr (in the order of `kinds`) for the assertions
    after the block.

        with BareNodes("/ns", ("task_manager", "sim")) as nodes:
            ... nodes.domain ...
        assert "..." in nodes.errs[0]
    """

    def __init__(self, namespace: str, kinds: tuple[str, ...], *ros_args: str,
                 per_node: dict[str, tuple[str, ...]] | None = None):
        self.namespace, self.kinds, self.ros_args = namespace, kinds, ros_args
        self.per_node = per_node or {}
        self.domain = node_suite.random_domain()
        self.procs: list[subprocess.Popen] = []
        self.errs: list[str] = []

    def __enter__(self) -> "BareNodes":
        env = dict(os.environ, ROS_DOMAIN_ID=str(self.domain))
        self.procs = [subprocess.Popen([str(bin_dir() / f"{kind}_node"), "--ros-args", "-r",
                                        f"__ns:={self.namespace}", *self.ros_args,
                                        *self.per_node.get(kind, ())],
                                       env=env, stderr=subprocess.PIPE, text=True)
                      for kind in self.kinds]
        return self

    def running(self) -> bool:
        return all(p.poll() is None for p in self.procs)

    def __exit__(self, *exc) -> None:
        for p in self.procs:
            p.send_signal(signal.SIGINT)
        self.errs = [p.communicate(timeout=10)[1] for p in self.procs]
        if exc[0] is None:
            assert all(p.returncode == 0 for p in self.procs), self.errs


def test_malformed_cdr_on_a_command_topic_is_logged_and_survived():
    """A writer whose type has the right name but the wrong layout: our sim cannot decode its
    samples; it must say so and keep serving well-formed commands."""
    from dataclasses import dataclass

    from cyclonedds.idl import IdlStruct
    from cyclonedds.idl import types as idl
    from cyclonedds.pub import DataWriter
    from cyclonedds.topic import Topic

    @dataclass
    class Garbage(IdlStruct, typename="sensor_msgs::msg::dds_::JointState_"):
        byte: idl.uint8

    with BareNodes("/mal", ("task_manager", "sim")) as nodes, \
            ros_agent.Agent(namespace="/mal", domain_id=nodes.domain) as agent:
        states = agent.subscribe("joint_states", "sensor_msgs/msg/JointState")
        observations = agent.subscribe("observation", "composuite_msgs/msg/Observation")
        command = agent.publisher("joint_command", "sensor_msgs/msg/JointState")
        reset = agent.service_client("reset", "composuite_msgs/srv/Reset", format="fastdds")
        reply, first = ros_agent.reset_with_joint_states(reset, states, seed=1)
        bad = DataWriter(agent.participant, Topic(agent.participant, "rt/mal/joint_command", Garbage),
                         qos=ros_agent.QOS_PROFILES["state"].to_dds())
        # Written before the sim's reader matched it, the garbage would simply be lost.
        deadline = time.monotonic() + 10
        while bad.get_publication_matched_status().current_count < 1:
            assert time.monotonic() < deadline, "the sim's joint_command reader never matched"
            time.sleep(0.05)
        for _ in range(3):
            bad.write(Garbage(byte=7))
        command.wait_for_subscribers(1, timeout=10)
        command.publish(name=list(first.name[:7]), position=list(first.position[:7]))
        observations.wait_for({"episode": reply.episode, "step": 1}, timeout=10)
    assert "unreadable joint_command dropped" in nodes.errs[1], nodes.errs[1]


def test_a_reply_written_before_the_clients_reader_exists_does_not_break_the_server():
    """A reset reply (~1.6 kB, with the related-sample-identity inline QoS every reply carries)
    written while the reply writer has matched no reader is fragmented at RustDDS' 1452-byte
    fallback budget. RustDDS 0.15.1 wrote such a DATA_FRAG one byte longer than it declared (the
    patched copy in third_party/ does not); with its debug assertions on, that panicked the task
    manager's DDS thread and the node went deaf. Provoke exactly that (a request with no reply
    reader), then call reset properly."""
    from cyclonedds.pub import DataWriter

    with BareNodes("/frag", ("task_manager", "sim"), "-p", "service_mapping:=cyclone") as nodes, \
            ros_agent.Agent(namespace="/frag", domain_id=nodes.domain) as agent:
        request_wire, _ = agent.types.cyclone_service("composuite_msgs/srv/Reset")
        request_topic, _ = ros_agent.service_topic_names("reset", "/frag")
        orphan = DataWriter(agent.participant, agent._topic(request_topic, request_wire),
                            qos=ros_agent.qos_profile("services").to_dds())
        deadline = time.monotonic() + 15
        while not ros_agent.matched_readers(orphan):
            assert time.monotonic() < deadline, "the task manager's reset server never matched"
            time.sleep(0.05)
        orphan.write(request_wire(client_guid=1, seq=1, seed=4, use_seed=True))
        time.sleep(1.0)  # the task manager answers into the void
        assert nodes.running()
        reset = agent.service_client("reset", "composuite_msgs/srv/Reset", format="cyclone")
        reply = reset.call({"seed": 5, "use_seed": True}, timeout=10)
        assert reply.success and reply.seed == 5, reply.message
        assert len(reply.observation.flat) > 0
    assert "reset: episode" in nodes.errs[0], nodes.errs[0]
    assert not any("panicked" in e for e in nodes.errs), nodes.errs


def test_reset_without_a_sim_fails_with_a_reason_instead_of_hanging():
    with BareNodes("/nosim", ("task_manager",), "-p", "reset_timeout:=0.5",
                   "-p", "service_mapping:=cyclone") as nodes, \
            ros_agent.Agent(namespace="/nosim", domain_id=nodes.domain) as agent:
        reset = agent.service_client("reset", "composuite_msgs/srv/Reset", format="cyclone")
        started = time.monotonic()
        reply = reset.call({"seed": 3, "use_seed": True}, timeout=10, retries=0)
        assert time.monotonic() - started < 3
        assert not reply.success
        assert "is sim_node running in this namespace?" in reply.message, reply.message


def test_demo_plays_the_expert_over_ros_identically_to_in_process():
    result = subprocess.run([composuite(), "demo", "--episodes", "1", "--seed", "0", "--json"],
                            env=dict(os.environ, ROS_DOMAIN_ID=str(node_suite.random_domain())),
                            capture_output=True, text=True, timeout=120)
    assert result.returncode == 0, result.stderr
    import json
    episodes = [json.loads(line) for line in result.stdout.splitlines() if line.startswith("{")]
    assert len(episodes) == 1
    assert episodes[0]["identical_to_in_process"] is True
    assert episodes[0]["success"] is True and episodes[0]["steps"] == 500


def test_robot_description_and_tf_static_place_the_arm_for_rviz():
    with BareNodes("/viz", ("task_manager", "sim"),
                   per_node={"task_manager": ("-p", "task:=Panda/box/no_obstacle/push")}) as nodes, \
            ros_agent.Agent(namespace="/viz", domain_id=nodes.domain) as agent:
        # Late joiners: both are latched (transient local).
        statics = agent.subscribe("tf_static", "tf2_msgs/msg/TFMessage", qos="latched")
        urdf = agent.subscribe("robot_description", "std_msgs/msg/String", qos="latched")
        transform = statics.wait_for(None, timeout=20).transforms[0]
        description = urdf.wait_for(None, timeout=20).data
    # Panda's URDF root link, at CompoSuite's robot base position
    # (docs/src/reference-facts.md §2.7: -0.5, -0.1, 0.912).
    assert transform.header.frame_id == "world" and transform.child_frame_id == "link0"
    t = transform.transform.translation
    assert (t.x, t.y, t.z) == (-0.5, -0.1, 0.912)
    assert '<link name="link0"' in description and "gripper_mount" in description
