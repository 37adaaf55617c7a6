"""Faults, and what the suite does about them: a node killed with SIGKILL mid-episode is started
again by `composuite launch` (--respawn); the agent's step in flight fails with a timeout that
names it; the next reset brings the environment back — observations bit-identical to the
in-process reference `env_replay` again, sim time still going forward, the scene, the
observations and the episode status agreeing on the episode. An agent killed mid-episode
leaves the suite serving the next one.

Each test has its own `composuite launch` (cyclone service format, a short respawn delay) in a
namespace of a random domain. Only run inside scripts/netns-isolate."""

# No `from __future__ import annotations`: cyclonedds resolves annotations at runtime.
import random
import subprocess
import sys
import textwrap
import time
from pathlib import Path

import pytest

from node_suite import Launched, env_replay_run, float_bits, ns_of
from ros_agent import Agent, LockstepClient, stamped

TASK = "Gen3/box/object_wall/pick_place"
STEP_TIMEOUT = 5.0
RESPAWN_DELAY = 0.5
HERE = Path(__file__).resolve().parent


class Stepper(LockstepClient):
    """A cyclonedds agent that keeps everything it receives, so a test can look at all of it."""

    def __init__(self, launched: Launched):
        self.launched = launched
        super().__init__(Agent(namespace=launched.namespace, domain_id=launched.domain))
        self.statuses = self.agent.subscribe("episode", "composuite_msgs/msg/EpisodeStatus")
        self.scenes = self.agent.subscribe("scene", "composuite_msgs/msg/Scene", qos="latched")

    def reset(self, seed: int, timeout: float = 30.0):
        """Reset until the suite answers with success and the episode's joint_states arrive (a
        restarted node needs discovery first; a reset meanwhile says the sim did not answer)."""
        deadline, last = time.monotonic() + timeout, None
        while time.monotonic() < deadline:
            try:
                reply = self.reset_client.call(seed=seed, use_seed=True, timeout=5, retries=0)
            except TimeoutError as error:
                last = str(error)
                continue
            last = reply.message
            if not reply.success:
                time.sleep(0.2)
                continue
            try:
                first = self.states.wait_for({"header.stamp": reply.observation.header.stamp}, timeout=2)
            except TimeoutError:
                continue
            self.started(reply, first)
            self.seed, self.stepped, self.commands = seed, [reply.observation], []
            self.rng = random.Random(seed)
            return reply
        raise AssertionError(f"no successful reset within {timeout} s (last: {last})\n"
                             f"{self.launched.text()[-4000:]}")

    def random_step(self) -> None:
        """A step to random targets near the start pose, kept for the comparison."""
        targets = [round(q + self.rng.uniform(-0.15, 0.15), 6) for q in self.home]
        observation = super().step(targets, timeout=STEP_TIMEOUT)
        self.commands.append({"joints": targets, "gripper": None})
        self.stepped.append(observation)

    def assert_like_the_reference(self) -> None:
        replay = env_replay_run({"task": TASK, "seed": self.seed, "commands": self.commands})
        assert [float_bits(o.flat) for o in self.stepped] == [float_bits(r["flat"]) for r in replay]
        rewards = [self.rewards.wait_for(self.this_episode(k), timeout=STEP_TIMEOUT)
                   for k in range(1, self.step_count + 1)]
        assert float_bits([r.total for r in rewards]) == float_bits([r["reward"] for r in replay[1:]])
        statuses = [self.statuses.wait_for(self.this_episode(k), timeout=STEP_TIMEOUT)
                    for k in range(1, self.step_count + 1)]
        assert all(s.seed == self.seed and not s.done for s in statuses)

    def warm_up(self, attempts: int = 10) -> None:
        """Reset and step once until observation, reward and episode status all arrive: each side
        sees a match on its own, and a volatile sample sent before the writer knew this agent's
        reader is not for us."""
        for _ in range(attempts):
            self.reset(seed=0)
            try:
                self.random_step()
                self.statuses.wait_for(self.this_episode(1), timeout=1)
                return
            except TimeoutError:
                continue
        raise AssertionError(f"observation, reward and episode never all arrived\n{self.launched.text()[-4000:]}")

    def close(self) -> None:
        self.agent.close()


@pytest.fixture
def launched(tmp_path, request):
    suite = Launched(tmp_path, f"/fault_{request.node.name[5:25]}", TASK,
                     "--respawn", "3", "--respawn-delay", str(RESPAWN_DELAY))
    yield suite
    suite.stop()


@pytest.fixture
def stepper(launched):
    s = Stepper(launched)
    s.warm_up()
    yield s
    s.close()


def run_then_kill(stepper: Stepper, launched: Launched, kind: str) -> int:
    """An episode of 10 steps, then `kind` killed; the largest stamp seen before."""
    stepper.reset(seed=5)
    for _ in range(10):
        stepper.random_step()
    before = max(ns_of(o.header.stamp) for o in stepper.observations.samples)
    launched.kill_node(kind)
    launched.wait_for_log(f"{kind} in {launched.namespace} exited on its own (killed by signal 9); "
                          "starting it again")
    launched.wait_for_log("(restart 1 of 3)")
    return before


def recovers(stepper: Stepper, before_ns: int) -> None:
    """What an agent does after a timed-out step: reset (until every node answers again), then
    an episode that must be right."""
    stepper.warm_up()
    stepper.reset(seed=8)
    for _ in range(30):
        stepper.random_step()
    stepper.assert_like_the_reference()
    # Time went on from before the crash, and the scene agrees with the episode stepped.
    assert all(ns_of(o.header.stamp) > before_ns for o in stepper.stepped)
    # The scene is latched: the latest one received is the episode being stepped. (Not "the
    # first with this episode number": a restarted task manager counts from 1 again.)
    scene = stepper.scenes.samples[-1]
    assert (scene.episode, scene.seed, scene.task.robot) == (stepper.episode, 8, TASK.split("/")[0])


def test_a_killed_sim_is_started_again_and_a_reset_brings_the_environment_back(launched, stepper):
    before = run_then_kill(stepper, launched, "sim")
    lost = stepper.episode
    # The step in flight: no sim to take it. The wait names the step it waited for.
    with pytest.raises(TimeoutError, match=rf"episode {stepper.episode} step {stepper.step_count + 1}"):
        stepper.random_step()
    recovers(stepper, before)
    assert stepper.episode > lost  # the task manager lived on: its count goes on
    # Never mixed: after the crash, the lost episode shows at most its step 0 again, bit for bit
    # what it was (the restarted sim's first scene), and nothing past it.
    replayed = [o for o in stepper.observations.samples if o.episode == lost]
    firsts = [o for o in replayed if o.step == 0]
    assert len(replayed) == len(firsts) + 10 and all(
        float_bits(o.flat) == float_bits(firsts[0].flat) for o in firsts), [o.step for o in replayed]


def test_a_killed_task_manager_is_started_again_and_a_reset_makes_scene_and_episode_agree(launched, stepper):
    before = run_then_kill(stepper, launched, "task_manager")
    launched.wait_for_log(f"{launched.namespace}/task_manager up", timeout=20)
    recovers(stepper, before)
    # The new task manager counts episodes from 1 again (an episode number may repeat one of the
    # old task manager's; the sim time, which the sim kept, tells them apart): what it announced
    # after the crash is what was stepped.
    statuses = [s for s in stepper.statuses.samples
                if s.episode == stepper.episode and ns_of(s.header.stamp) > before]
    assert [s.step for s in statuses] == list(range(0, 31)) and all(s.seed == 8 for s in statuses)


def test_a_killed_reward_node_is_started_again_and_rewards_follow_the_next_reset(launched, stepper):
    before = run_then_kill(stepper, launched, "reward")
    launched.wait_for_log(f"{launched.namespace}/reward up", timeout=20)
    recovers(stepper, before)


AGENT = textwrap.dedent("""
    import random, sys
    from ros_agent import Agent, LockstepClient, stamped
    namespace, domain = sys.argv[1], int(sys.argv[2])
    with Agent(namespace=namespace, domain_id=domain) as agent:
        client = LockstepClient(agent)
        client.reset(seed=2)
        client.command.wait_for_subscribers(1, timeout=20)
        rng = random.Random(0)
        for k in range(1, 1000):
            client.step([q + rng.uniform(-0.1, 0.1) for q in client.home], timeout=10, reward=False)
            print(k, flush=True)
""")


def test_an_agent_killed_mid_episode_leaves_the_suite_serving_the_next(launched, stepper):
    first_agent = subprocess.Popen([sys.executable, "-c", AGENT, launched.namespace, str(launched.domain)],
                                   cwd=HERE, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    try:
        for _ in range(20):  # it is stepping
            line = first_agent.stdout.readline()
            assert line, first_agent.stderr.read()
        first_agent.kill()
        first_agent.wait()
    finally:
        if first_agent.poll() is None:
            first_agent.kill()
    # The killed agent's last command may still be on its way to the sim, and a reset sent at once
    # can overtake it (the sim serves scene before joint_command). Its stamp (the observation it
    # answered) is older than the new episode, so the sim drops it instead of stepping the new
    # episode with it: the next agent resets at once.
    stepper.reset(seed=8)
    for _ in range(30):
        stepper.random_step()
    stepper.assert_like_the_reference()
    assert launched.process.poll() is None
    assert "exited on its own" not in launched.text()


def test_a_command_stamped_before_the_episode_began_does_not_step_it(launched, stepper):
    """A joint_command answering an earlier episode's observation (in flight from an agent that
    died while another reset) is dropped with a log line; one answering this episode's steps it."""
    stepper.reset(seed=3)
    old = stepper.since  # this episode's step-0 stamp
    stepper.random_step()
    stepper.reset(seed=4)
    assert stepper.since > old
    stepper.command.publish(name=stepper.names, position=stepper.home, header=stamped(old))
    launched.wait_for_log("joint_command dropped")
    with pytest.raises(TimeoutError):
        stepper.observations.wait_for(stepper.this_episode(1), timeout=1.0)
    for _ in range(5):
        stepper.random_step()  # stamped with this episode's observations: each steps it
    stepper.assert_like_the_reference()


def test_a_reference_action_stamped_before_the_episode_began_does_not_step_it(launched, stepper):
    """The same for the reference benchmark's action (`reference_action_stamped`, what the
    Gymnasium package sends): one answering an earlier episode is dropped with a log line; one
    answering this episode's step-0 observation steps it, and an unstamped one is taken."""
    actions = stepper.agent.publisher("reference_action_stamped", "composuite_msgs/msg/ReferenceAction")
    actions.wait_for_subscribers(1, timeout=20)
    stepper.reset(seed=3)
    old = stepper.since
    stepper.random_step()
    stepper.reset(seed=4)
    hold = [0.0] * 8
    actions.publish(header=stamped(old), action=hold)
    launched.wait_for_log("reference_action_stamped dropped")
    with pytest.raises(TimeoutError):
        stepper.observations.wait_for(stepper.this_episode(1), timeout=1.0)
    actions.publish(header=stamped(stepper.since), action=hold)
    stepper.observations.wait_for(stepper.this_episode(1), timeout=STEP_TIMEOUT)
    actions.publish(action=hold)  # unstamped
    stepper.observations.wait_for(stepper.this_episode(2), timeout=STEP_TIMEOUT)
