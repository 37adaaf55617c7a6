"""`composuite bag play`: a recorded session published again into a graph, checked by a real
rclpy subscriber (ROS 2 Jazzy, Fast DDS) taking the raw CDR bytes: every message of the played
topics arrives, in order, byte for byte as the `mcap` library reads it from the file; the latched
topic is offered latched, a remapped one arrives under its new name (a transient-local subscription matches it); the pace follows --rate
(half speed here);
--clock publishes the bag's time.

Only run inside scripts/netns-isolate."""

import os
import re
import subprocess
from pathlib import Path

import pytest
from rclpy.qos import DurabilityPolicy, HistoryPolicy, QoSProfile, ReliabilityPolicy

import node_suite
from rclpy_agent import RclpyAgent
from test_recorder import composuite, metadata
from test_session import session

TASK = "Panda/box/no_obstacle/push"
RATE = 0.5
CLOCK_HZ = 50.0


@pytest.fixture(scope="module")
def bag(tmp_path_factory) -> Path:
    out = tmp_path_factory.mktemp("play") / "s"
    result = session("--tasks", TASK, "--episodes", "1", "--policy", "random", "--horizon", "40",
                     "--seed", "3", "--out", str(out))
    assert result.returncode == 0, result.stderr[-4000:]
    return out / "bag"


def recorded_bytes(bag: Path, topics: set[str]) -> dict[str, list[bytes]]:
    """The CDR bytes of every message on `topics`, in log-time order, read with `mcap`."""
    from mcap.reader import make_reader

    out: dict[str, list[tuple[int, bytes]]] = {t: [] for t in topics}
    for path in sorted(bag.glob("*.mcap")):
        with open(path, "rb") as f:
            for _, channel, message in make_reader(f).iter_messages(topics=list(topics), log_time_order=True):
                out[channel.topic].append((message.log_time, message.data))
    return {t: [data for _, data in sorted(messages, key=lambda m: m[0])] for t, messages in out.items()}


def topic_ending(bag: Path, suffix: str) -> str:
    (name,) = [t["topic_metadata"]["name"] for t in metadata(bag)["topics_with_message_count"]
               if t["topic_metadata"]["name"].endswith(suffix)]
    return name


def test_play_republishes_every_message_as_recorded(bag):
    from composuite_msgs.msg import Observation
    from rosgraph_msgs.msg import Clock
    from std_msgs.msg import String

    observation, description = topic_ending(bag, "/observation"), topic_ending(bag, "/robot_description")
    recorded = recorded_bytes(bag, {observation, description})
    assert len(recorded[observation]) >= 41 and len(recorded[description]) >= 1  # 40 steps + step 0
    domain = node_suite.random_domain()
    agent = RclpyAgent(domain)
    received: dict[str, list[bytes]] = {observation: [], description: []}
    replayed = "/replayed/observation"  # played under another name (--remap)
    clock: list[int] = []
    try:
        reliable = dict(reliability=ReliabilityPolicy.RELIABLE, history=HistoryPolicy.KEEP_ALL)
        agent.node.create_subscription(Observation, replayed, received[observation].append,
                                       QoSProfile(durability=DurabilityPolicy.VOLATILE, **reliable),
                                       raw=True)
        # Transient local: matches only a publisher that offers it (as the sim's does).
        agent.node.create_subscription(String, description, received[description].append,
                                       QoSProfile(durability=DurabilityPolicy.TRANSIENT_LOCAL, **reliable),
                                       raw=True)
        agent.node.create_subscription(
            Clock, "/clock", lambda m: clock.append(m.clock.sec * 10**9 + m.clock.nanosec),
            QoSProfile(depth=1000, reliability=ReliabilityPolicy.BEST_EFFORT))
        player = subprocess.Popen(
            [str(node_suite.node_dir() / "composuite"), "bag", "play", str(bag), "--rate", str(RATE),
             "--clock", str(CLOCK_HZ), "--delay", "2", "--topics", observation, description,
             "--remap", f"{observation}:={replayed}"],
            env=dict(os.environ, ROS_DOMAIN_ID=str(domain)), stdout=subprocess.PIPE, stderr=subprocess.PIPE,
            text=True)
        agent.spin_until(lambda: player.poll() is not None, timeout=60, what="the player to finish")
        stdout, stderr = player.communicate()
        assert player.returncode == 0, stderr
        agent.spin_until(lambda: all(len(received[t]) >= len(recorded[t]) for t in received), timeout=5,
                         what="every played message")
    finally:
        agent.close()
    for topic in received:
        assert received[topic] == recorded[topic], f"{topic}: not byte for byte what was recorded"
    # The pace: the bag's span over the rate (plus scheduling slack).
    match = re.search(r"played (\d+) messages on 2 topics and (\d+) /clock ticks: ([\d.]+) s of bag time "
                      r"in ([\d.]+) s", stdout)
    assert match, stdout
    span, wall = float(match[3]), float(match[4])
    assert int(match[1]) == sum(len(v) for v in recorded.values())
    assert span > 0.3, "a 40-step lockstep session spans most of a second"
    assert span / RATE * 0.95 <= wall <= span / RATE + 0.5, (span, wall)
    # The clock: the bag's time from its first played message, RATE / CLOCK_HZ s apart.
    assert len(clock) >= 0.8 * wall * CLOCK_HZ, (len(clock), wall)
    steps = {b - a for a, b in zip(clock, clock[1:])}
    assert all(abs(step - RATE / CLOCK_HZ * 1e9) < 1e3 for step in steps), sorted(steps)[:5]


def test_bad_play_arguments_are_named(bag):
    bad_rate = composuite("bag", "play", str(bag), "--rate", "0", check=False)
    assert bad_rate.returncode != 0 and "rate 0 is invalid" in bad_rate.stderr
    unknown = composuite("bag", "play", str(bag), "--topics", "/nope", "--delay", "0", check=False)
    assert unknown.returncode != 0 and "/nope is not in the bag; its topics:" in unknown.stderr
    bad_remap = composuite("bag", "play", str(bag), "--remap", "tf:=/tf", check=False)
    assert bad_remap.returncode != 0 and "remap `tf:=/tf` is invalid" in bad_remap.stderr
    not_a_bag = composuite("bag", "play", str(bag.parent), "--delay", "0", check=False)
    assert not_a_bag.returncode != 0 and "metadata.yaml" in not_a_bag.stderr
