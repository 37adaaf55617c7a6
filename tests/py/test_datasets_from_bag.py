"""`composuite-dataset from-bag`: a recorded session (`composuite launch --record`) whose agent
acted in the reference's action space (`reference_action_stamped`, from a cyclonedds agent)
becomes a dataset whose rows are what the agent saw (float32) and which `verify` re-simulates;
a session driven by `joint_command` is refused, saying why. And the other way round: an `expert`
file's episode, its stored actions played through the node suite, is what the suite publishes,
bit for bit.

Only run inside scripts/netns-isolate."""

# No `from __future__ import annotations`: cyclonedds resolves annotations at runtime.
import time

import numpy as np
import pytest

from node_suite import Launched, ns_of
from ros_agent import Agent, LockstepClient, stamped

from composuite_ros import datasets
from composuite_ros.datasets import DatasetError
from composuite_ros.datasets.from_bag import from_bag

TASK = "Jaco/box/no_obstacle/push"
FOLDER = "Jaco_Box_None_Push"
EPISODES = [(3, 25), (4, 15)]  # (seed, steps)


class ReferenceAgent(LockstepClient):
    """A lockstep agent that acts with the reference's 8 numbers (reference_action_stamped)."""

    def __init__(self, launched: Launched):
        super().__init__(Agent(namespace=launched.namespace, domain_id=launched.domain))
        self.reference = self.agent.publisher("reference_action_stamped",
                                              "composuite_msgs/msg/ReferenceAction")
        self.launched = launched

    def wait_until_recorded(self, command_topic: str) -> None:
        """Until the sim and the recorder read our commands and the recorder records the
        environment's topics (messages before that are not the session's)."""
        self.reset_client.wait_for_service(timeout=20)
        publisher = self.reference if command_topic == "reference_action_stamped" else self.command
        publisher.wait_for_subscribers(2, timeout=20)
        for topic in (self.observations, self.rewards, self.states):
            topic.wait_for_publishers(timeout=20)
        for topic in ("observation", "scene", "reward", command_topic):
            self.launched.wait_for_log(f"recording {self.launched.namespace}/{topic} ")
        time.sleep(0.5)

    def act(self, action) -> object:
        """One lockstep step with a reference action; its observation."""
        self.reference.publish(header=stamped(self.answered), action=[float(v) for v in action])
        self.step_count += 1
        want = self.this_episode(self.step_count)
        observation = self.observations.wait_for(want, timeout=5)
        self.answered = ns_of(observation.header.stamp)
        self.reward = self.rewards.wait_for(want, timeout=5)
        return observation


def record(tmp_path, namespace: str, drive) -> object:
    bag = tmp_path / "bag"
    launched = Launched(tmp_path, namespace, TASK, "--record", str(bag))
    agent = ReferenceAgent(launched)
    try:
        seen = drive(agent)
        time.sleep(0.3)
    finally:
        agent.agent.close()
        launched.stop()
    return bag, seen


def test_a_reference_action_session_becomes_a_dataset_that_verifies(tmp_path):
    rng = np.random.default_rng(7)

    def drive(agent):
        agent.wait_until_recorded("reference_action_stamped")
        seen = []
        for seed, steps in EPISODES:
            reply = agent.reset(seed=seed)
            rows = [np.asarray(reply.observation.flat)]
            actions = rng.uniform(-1, 1, size=(steps, 8)).astype(np.float32)
            for action in actions:
                rows.append(np.asarray(agent.act(action).flat))
            seen.append((seed, actions, np.array(rows)))
        return seen

    bag, seen = record(tmp_path, "/dsbag", drive)
    (path,) = from_bag(bag, tmp_path / "data", command="test")
    assert path == tmp_path / "data" / "from-bag" / FOLDER / "data.hdf5"
    data = datasets.open_task(path)
    assert [(s, b - a) for a, b, s in data.episodes()] == [(3, 25), (4, 15)]
    for (a, b, _), (seed, actions, rows) in zip(data.episodes(), seen):
        assert np.array_equal(data["actions"][a:b], actions)
        assert np.array_equal(data["observations"][a:b], rows[:-1].astype(np.float32))
        assert data["timeouts"][b - 1] == 1  # the agent stopped the episode there: cut
    assert np.array_equal(data["episode_final_observations"][1], seen[1][2][-1].astype(np.float32))
    verdict = datasets.verify(path)
    assert verdict.ok, verdict.difference


def test_a_session_driven_by_joint_command_is_refused(tmp_path):
    def drive(agent):
        agent.wait_until_recorded("joint_command")
        agent.reset(seed=1)
        for k in range(5):
            agent.step([q + 0.01 * k for q in agent.home])

    bag, _ = record(tmp_path, "/dsjoint", drive)
    with pytest.raises(DatasetError, match="driven by joint_command.*not in the reference's "
                                           "action space.*--policy planned"):
        from_bag(bag, tmp_path / "data")
    assert not (tmp_path / "data").exists()


def test_an_expert_episode_plays_through_the_suite_as_its_file_stores_it(tmp_path):
    """The planned expert's episode of TASK as its `expert` file stores it, played from the
    stored actions through the node suite (reference_action_stamped, lockstep): every
    observation and reward the suite publishes is the file's, bit for bit (float32), the suite
    reports the same successes, and the recorded session becomes the same rows again."""
    [expert] = datasets.generate(tmp_path / "expert", datasets.select_tasks([TASK]), ["expert"],
                                 transitions=500, threads=1, command="test")
    data = datasets.open_task(expert)
    [(a, b, seed)] = data.episodes()
    actions = data["actions"][a:b]
    assert data["successes"][a:b].any(), "the expert solves TASK on this seed"

    def drive(agent):
        agent.wait_until_recorded("reference_action_stamped")
        reply = agent.reset(seed=int(seed))
        rows, rewards, successes = [np.asarray(reply.observation.flat)], [], []
        for action in actions:
            rows.append(np.asarray(agent.act(action).flat))
            rewards.append(agent.reward.total)
            successes.append(agent.reward.success)
        return np.array(rows), np.array(rewards), np.array(successes)

    bag, (rows, rewards, successes) = record(tmp_path, "/dsexpert", drive)
    assert np.array_equal(rows[:-1].astype(np.float32), data["observations"][a:b])
    assert np.array_equal(rewards.astype(np.float32), data["rewards"][a:b])
    assert np.array_equal(successes, data["successes"][a:b].astype(bool))
    (path,) = from_bag(bag, tmp_path / "data", command="test")
    again = datasets.open_task(path)
    assert np.array_equal(again["actions"], actions)
    assert np.array_equal(again["observations"], data["observations"][a:b])
