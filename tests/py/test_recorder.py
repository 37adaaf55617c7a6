"""The recorder node (`composuite launch --record DIR`) judged by readers nobody here wrote: the
`rosbags` library opens the rosbag2 directory (checking every RIHS01 hash against the embedded
definitions) and decodes every message; the `mcap` library reads each file with CRC checks and
its summary agrees with metadata.yaml; what the bag holds equals what a subscriber saw and what
the publishers sent, message for message. Then the crash cases: SIGTERM closes a complete bag,
SIGKILL leaves every flushed chunk readable and `composuite bag reindex` makes it a bag again, and
a recorder that cannot write says so while the suite keeps serving.

Only run inside scripts/netns-isolate."""

# No `from __future__ import annotations`: cyclonedds resolves annotations at runtime.
import json
import os
import signal
import subprocess
import time
from pathlib import Path

import pytest
import yaml

import msgcheck
import node_suite
from node_suite import Launched, float_bits, node_processes, ns_of
from ros_agent import Agent, LockstepClient

TASK = "IIWA/box/no_obstacle/pick_place"
NS = "/rec"
# Every topic an environment has, and the agent's command topic.
ENV_TOPICS = ["clock", "episode", "joint_states", "observation", "reward", "robot_description", "scene",
              "success", "tf", "tf_static", "world_state", "scene_markers", "object_markers", "joint_command"]
EPISODES = [(3, 40), (4, 30)]  # (seed, steps)


def composuite(*args: str, check: bool = True) -> subprocess.CompletedProcess:
    result = subprocess.run([str(node_suite.node_dir() / "composuite"), *args],
                            capture_output=True, text=True, timeout=120)
    if check:
        assert result.returncode == 0, f"composuite {' '.join(args)}: {result.stderr}"
    return result


class RecordingAgent(LockstepClient):
    """A cyclonedds agent that also keeps world_state and episode, to compare with the bag."""

    def __init__(self, launched: Launched):
        super().__init__(Agent(namespace=launched.namespace, domain_id=launched.domain))
        self.worlds = self.agent.subscribe("world_state", "composuite_msgs/msg/WorldState")
        self.statuses = self.agent.subscribe("episode", "composuite_msgs/msg/EpisodeStatus")
        self.launched = launched

    def wait_for_suite(self, command_readers: int = 2) -> None:
        """Until the services answer and every topic this agent uses is matched both ways (a
        volatile sample published before the writer knew our reader is not ours), with
        `command_readers` readers of joint_command (the sim, and the recorder when it runs)."""
        self.reset_client.wait_for_service(timeout=20)
        self.command.wait_for_subscribers(command_readers, timeout=20)
        for topic in (self.observations, self.rewards, self.statuses, self.worlds, self.states):
            topic.wait_for_publishers(timeout=20)
        time.sleep(0.5)

    def wait_until_recorded(self) -> None:
        """Until the recorder subscribed to every topic of the environment (it logs each), plus a
        moment for its readers to match: messages sent before that are not the session's."""
        self.wait_for_suite()
        for topic in ENV_TOPICS:
            self.launched.wait_for_log(f"recording {self.launched.namespace}/{topic} ")
        time.sleep(0.5)

    def run_episodes(self) -> int:
        """Run EPISODES; the stamp (ns) of the first reset's observation."""
        since = None
        for seed, steps in EPISODES:
            reply = self.reset(seed=seed)
            since = since or ns_of(reply.observation.header.stamp)
            for k in range(steps):
                self.step([q + 0.02 * ((k % 7) - 3) for q in self.home])
        self.statuses.wait_for(self.this_episode(EPISODES[-1][1]), timeout=5)
        return since


@pytest.fixture(scope="module")
def session(tmp_path_factory):
    """One recorded session: two episodes in lockstep, then Ctrl-C. What the agent saw, the bag."""
    log_dir = tmp_path_factory.mktemp("recorded")
    bag = log_dir / "session"
    launched = Launched(log_dir, NS, TASK, "--record", str(bag))
    agent = RecordingAgent(launched)
    try:
        agent.wait_until_recorded()
        since = agent.run_episodes()
        time.sleep(0.3)
        seen = {
            "observation": agent.observations.samples, "reward": agent.rewards.samples,
            "world_state": agent.worlds.samples, "episode": agent.statuses.samples,
            "joint_states": agent.states.samples,
        }
    finally:
        agent.agent.close()
        launched.stop()
    assert "bag " + str(bag) + " closed" in launched.text()
    return {"bag": bag, "since": since, "seen": seen, "log": launched.text()}


def bag_messages(bag: Path) -> dict[str, list]:
    """{topic: [(log_time, message)]} read with rosbags' AnyReader (which checks every type hash
    of metadata.yaml against the definitions embedded in the MCAP schemas)."""
    from rosbags.highlevel import AnyReader

    out: dict[str, list] = {}
    with AnyReader([bag], default_typestore=msgcheck.rosbags_store()) as reader:
        assert reader.connections, "rosbags found no topics"
        for connection, timestamp, raw in reader.messages():
            out.setdefault(connection.topic, []).append((timestamp, reader.deserialize(raw, connection.msgtype)))
    return out


def metadata(bag: Path) -> dict:
    return yaml.safe_load((bag / "metadata.yaml").read_text())["rosbag2_bagfile_information"]


def stamped_after(messages, since: int) -> list:
    return [m for m in messages if ns_of(m.header.stamp) >= since]


def test_rosbags_reads_every_message_and_it_is_what_the_subscriber_saw(session):
    recorded = bag_messages(session["bag"])
    info = metadata(session["bag"])
    counts = {t["topic_metadata"]["name"]: t["message_count"] for t in info["topics_with_message_count"]}
    assert {t: len(m) for t, m in recorded.items()} == {t: c for t, c in counts.items() if c}
    for topic in ENV_TOPICS:
        assert f"{NS}/{topic}" in counts, f"{topic} not recorded"
    since = session["since"]
    for topic, key in [("observation", lambda m: float_bits(m.flat)), ("reward", lambda m: float_bits([m.total])),
                       ("world_state", lambda m: (m.episode, m.step, float_bits([m.object_pose.position.x]))),
                       ("episode", lambda m: (m.episode, m.step, m.done, float_bits([m.episode_return])))]:
        in_bag = [(ns_of(m.header.stamp), key(m)) for _, m in recorded[f"{NS}/{topic}"]]
        seen = [(ns_of(m.header.stamp), key(m)) for m in session["seen"][topic]]
        assert [x for x in in_bag if x[0] >= since] == [x for x in seen if x[0] >= since], topic


def test_every_message_the_publishers_sent_is_in_the_bag(session):
    """Lockstep: per episode one step-0 observation, then one per command."""
    recorded = bag_messages(session["bag"])
    since = session["since"]
    commands = sum(steps for _, steps in EPISODES)
    assert len(recorded[f"{NS}/joint_command"]) == commands
    observations = stamped_after([m for _, m in recorded[f"{NS}/observation"]], since)
    assert len(observations) == commands + len(EPISODES)
    assert [(o.episode, o.step) for o in observations][:3] == [(observations[0].episode, k) for k in range(3)]
    for topic in ("joint_states", "world_state", "tf", "object_markers"):
        msgs = [m for _, m in recorded[f"{NS}/{topic}"]]
        stamps = [ns_of(m.transforms[0].header.stamp) if topic == "tf"
                  else ns_of(m.markers[0].header.stamp) if topic == "object_markers"
                  else ns_of(m.header.stamp) for m in msgs]
        assert len([s for s in stamps if s >= since]) == commands + len(EPISODES), topic
    rewards = stamped_after([m for _, m in recorded[f"{NS}/reward"]], since)
    assert [(r.episode, r.step) for r in rewards] == [
        (o.episode, o.step) for o in observations if o.step > 0] or len(rewards) == commands + len(EPISODES)


def test_mcap_reader_with_crc_checks_agrees_with_metadata(session):
    from mcap.reader import make_reader
    from mcap_ros2.decoder import DecoderFactory

    bag, info = session["bag"], metadata(session["bag"])
    assert info["version"] == 9 and info["storage_identifier"] == "mcap" and info["ros_distro"] == "jazzy"
    assert info["relative_file_paths"] == ["session_0.mcap"]
    per_channel: dict[str, int] = {}
    with open(bag / "session_0.mcap", "rb") as f:
        reader = make_reader(f, validate_crcs=True, decoder_factories=[DecoderFactory()])
        assert reader.get_header().profile == "ros2"
        summary = reader.get_summary()
        assert summary.statistics.message_count == info["message_count"]
        for schema in summary.schemas.values():
            assert schema.encoding == "ros2msg", schema.name
            assert schema.data, schema.name
        for channel in summary.channels.values():
            assert channel.message_encoding == "cdr"
            assert set(channel.metadata) == {"offered_qos_profiles", "topic_type_hash"}
            assert channel.metadata["topic_type_hash"].startswith("RIHS01_"), channel.topic
        records = list(reader.iter_metadata())
        assert [r.name for r in records] == ["rosbag2", "rosbag2"]
        assert yaml.safe_load(records[-1].metadata["serialized_metadata"])["message_count"] == info["message_count"]
        for schema, channel, message, decoded in reader.iter_decoded_messages():
            per_channel[channel.topic] = per_channel.get(channel.topic, 0) + 1
            if channel.topic == f"{NS}/observation":
                assert len(decoded.flat) == 93
    assert per_channel == {t["topic_metadata"]["name"]: t["message_count"]
                           for t in info["topics_with_message_count"] if t["message_count"]}


def test_metadata_records_each_topics_offered_qos(session):
    info = metadata(session["bag"])
    topics = {t["topic_metadata"]["name"]: t["topic_metadata"] for t in info["topics_with_message_count"]}
    profile = topics[f"{NS}/scene"]["offered_qos_profiles"][0]
    assert list(profile) == ["history", "depth", "reliability", "durability", "deadline", "lifespan",
                             "liveliness", "liveliness_lease_duration", "avoid_ros_namespace_conventions"]
    assert (profile["reliability"], profile["durability"]) == ("reliable", "transient_local")
    for latched in ("robot_description", "tf_static", "scene_markers"):
        (offered,) = topics[f"{NS}/{latched}"]["offered_qos_profiles"]
        assert (offered["reliability"], offered["durability"]) == ("reliable", "transient_local"), latched
    for volatile in ("tf", "object_markers"):
        (offered,) = topics[f"{NS}/{volatile}"]["offered_qos_profiles"]
        assert (offered["reliability"], offered["durability"]) == ("reliable", "volatile"), volatile
    assert topics[f"{NS}/scene_markers"]["type"] == "visualization_msgs/msg/MarkerArray"
    clock = topics[f"{NS}/clock"]["offered_qos_profiles"][0]
    assert (clock["reliability"], clock["durability"]) == ("best_effort", "volatile")
    assert profile["deadline"] == {"sec": 9223372036, "nsec": 854775807}
    assert topics[f"{NS}/observation"]["type"] == "composuite_msgs/msg/Observation"


def test_bag_episodes_equal_a_recomputation_with_rosbags(session):
    bag = session["bag"]
    ours = json.loads(composuite("bag", "episodes", str(bag), "--json").stdout)
    recorded = bag_messages(bag)
    by_episode: dict[int, dict] = {}
    for _, s in recorded[f"{NS}/episode"]:
        row = by_episode.setdefault(s.episode, {"suite_episode": s.episode, "seed": s.seed, "length": 0})
        if s.step >= row["length"]:
            row.update(length=s.step, done=s.done, success=s.success_seen, **{"return": s.episode_return})
    stages: dict[int, int] = {}
    for _, r in recorded[f"{NS}/reward"]:
        if r.step > 0:  # step 0 is the reset state, not a step taken
            stages[r.episode] = max(stages.get(r.episode, -1), r.current_stage)
    # Episodes that took a step (set_task's own episode ends at the seeded reset, at step 0),
    # numbered 1, 2, … in the order they started; the topic's own numbers as suite_episode.
    stepped = [(e, row) for e, row in sorted(by_episode.items()) if row["length"] > 0]
    expected = [dict(row, episode=n, furthest_stage=stages.get(e, -1), task=TASK, namespace=NS)
                for n, (e, row) in enumerate(stepped, start=1)]
    assert [{k: e[k] for k in expected[0]} for e in ours] == expected
    assert [(e["seed"], e["length"]) for e in ours][-2:] == EPISODES
    assert ours[-2]["done"] and not ours[-1]["done"]
    info = json.loads(composuite("bag", "info", str(bag), "--json").stdout)
    assert info["messages"] == metadata(bag)["message_count"]
    assert info["episodes"] == len(ours)
    text = composuite("bag", "info", str(bag)).stdout
    assert "Storage id:        mcap" in text and f"Topic: {NS}/observation" in text


def test_sigterm_closes_and_sigkill_leaves_a_bag_reindex_restores(tmp_path):
    for how in (signal.SIGTERM, signal.SIGKILL):
        bag = tmp_path / f"killed_{how.name}"
        launched = Launched(tmp_path, f"{NS}_{how.name.lower()}", TASK, "--record", str(bag))
        agent = RecordingAgent(launched)
        try:
            agent.wait_until_recorded()
            reply = agent.reset(seed=5)
            since = ns_of(reply.observation.header.stamp)
            for _ in range(60):
                agent.step(agent.home)
            time.sleep(1.5)  # > flush_period: every step's messages are in a finished chunk
            (recorder,) = node_processes("", "recorder")
            os.kill(recorder, how)
            launched.wait_for_log("the suite goes on without recording" if how == signal.SIGKILL
                                  else f"recorder in {launched.namespace} exited on its own (exit code 0)")
            for _ in range(5):  # the environment keeps serving
                agent.step(agent.home)
        finally:
            agent.agent.close()
            launched.stop()
        if how == signal.SIGTERM:
            assert (bag / "metadata.yaml").exists()
        else:
            assert not (bag / "metadata.yaml").exists()
            result = composuite("bag", "info", str(bag), check=False)
            assert result.returncode == 2 and "bag reindex" in result.stderr
            out = composuite("bag", "reindex", str(bag))
            assert "reindexed" in out.stdout and "rewritten from its complete chunks" in out.stderr
        recorded = bag_messages(bag)
        observations = stamped_after([m for _, m in recorded[f"{launched.namespace}/observation"]], since)
        assert len(observations) == 61, how.name
        assert len(recorded[f"{launched.namespace}/joint_command"]) == 60, how.name


def test_bad_record_targets_are_named_and_the_suite_keeps_serving(tmp_path):
    existing = tmp_path / "exists"
    existing.mkdir()
    result = composuite("launch", "--task", TASK, "--record", str(existing), "--duration", "1", check=False)
    assert result.returncode == 2 and "exists already" in result.stderr
    result = composuite("launch", "--record-regex", "(", "--record", str(tmp_path / "x"), check=False)
    assert result.returncode == 2 and "--record-regex" in result.stderr
    result = composuite("launch", "--record-max-bag-duration", "0", "--record", str(tmp_path / "x"), check=False)
    assert result.returncode == 2 and "--record-max-bag-duration 0 is invalid; seconds > 0" in result.stderr
    result = composuite("node", "recorder", "--ros-args", "-p", "all:=true", check=False)
    assert result.returncode != 0 and "-p output:=DIR" in result.stderr
    result = composuite("node", "recorder", "--ros-args", "-p", f"output:={tmp_path / 'y'}", check=False)
    assert result.returncode != 0 and "nothing to record" in result.stderr
    # A directory the recorder cannot create: it says so, the environment keeps serving.
    launched = Launched(tmp_path, f"{NS}_unwritable", TASK, "--record", "/proc/composuite-bag")
    agent = RecordingAgent(launched)
    try:
        launched.wait_for_log("the suite goes on without recording")
        assert "cannot create bag directory /proc/composuite-bag" in launched.text()
        agent.wait_for_suite(command_readers=1)
        agent.reset(seed=1)
        for _ in range(3):
            agent.step(agent.home)
    finally:
        agent.agent.close()
        launched.stop()
