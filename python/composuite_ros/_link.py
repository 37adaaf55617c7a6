"""The ROS side of the Gymnasium envs: one rclpy participant, and one `Channel` per environment
of the suite (per namespace) with its topics, services and what arrived on them.

Lessons this follows (rclpy 7.1.6 on Fast DDS; the book's Performance chapter,
docs/src/performance.md, has the figures):
- a private `Context` and an own `SingleThreadedExecutor` polled with `spin_once`: nothing spins
  in the background, so `close()` leaves no thread, and no `spin_until_future_complete` (it slows
  down with every service call in that release);
- every wait has a wall-clock deadline and says what it waited for;
- step messages are matched by (episode, step), never "the latest message";
- each side of a DDS match learns of it on its own: a volatile sample sent before the sender
  knows this reader is lost. Before the first step a channel waits until every topic matched here
  and a reset's step-0 observation, reward and episode status all arrived (so each of the three
  writers knows this participant's reader); otherwise it asks the same reset again.
"""

from __future__ import annotations

import contextlib
import itertools
import math
import time
import xml.etree.ElementTree as ElementTree
from collections.abc import Callable
from dataclasses import dataclass, fields as dataclass_fields

import numpy as np
import rclpy
from builtin_interfaces.msg import Time
from composuite_msgs.msg import EpisodeStatus, Observation, ReferenceAction, StagedReward
from composuite_msgs.srv import Reset, SampleTasks, SetTask
from rclpy.context import Context
from rclpy.event_handler import PublisherEventCallbacks, SubscriptionEventCallbacks
from rclpy.executors import SingleThreadedExecutor
from rclpy.impl.implementation_singleton import rclpy_implementation as _rclpy
from rclpy.qos import DurabilityPolicy, HistoryPolicy, QoSProfile, ReliabilityPolicy
from sensor_msgs.msg import JointState
from std_msgs.msg import Header, String

from ._cdr import FieldReader
from .errors import StepLostError, SuiteNotRunningError
from .tasks import Task

# The suite's QoS (ROS defaults): state topics reliable/volatile/keep-last-10; latched topics
# (robot_description) transient local, keep last 1.
STATE_QOS = QoSProfile(depth=10, reliability=ReliabilityPolicy.RELIABLE,
                       durability=DurabilityPolicy.VOLATILE, history=HistoryPolicy.KEEP_LAST)
LATCHED_QOS = QoSProfile(depth=1, reliability=ReliabilityPolicy.RELIABLE,
                         durability=DurabilityPolicy.TRANSIENT_LOCAL, history=HistoryPolicy.KEEP_LAST)

ARM_JOINTS = 7
# How long a service request may stay unanswered before it is sent again, attempt after attempt
# (a reply sent before the server's reply writer matched this client is lost, see the module
# doc; that happens on a first call, so the first resend comes soon). Later attempts wait 3 s.
ATTEMPT_BUDGETS_S = (0.5, 1.0, 2.0)
LATER_ATTEMPT_S = 3.0


def attempt_budget(attempt: int) -> float:
    return ATTEMPT_BUDGETS_S[attempt] if attempt < len(ATTEMPT_BUDGETS_S) else LATER_ATTEMPT_S
# How long the step-0 messages of a reset (observation, reward, episode status) may take to
# arrive before the reset is asked again. Their arrival is the proof that each of the three
# writers has matched this participant's reader: a step's messages are volatile, so a step
# published before that match would be lost.
STEP0_WAIT_S = 1.0
# First contact (discovery of every endpoint) may take this many times the step timeout: RustDDS
# and Fast DDS announce endpoints again only every few seconds when a first announcement is lost,
# which happens on a loaded machine.
DISCOVERY_TIMEOUT_FACTOR = 3.0


def normalize_namespace(namespace: str) -> str:
    """`env_00`, `/env_00/` → `/env_00`; `` or `/` → `/`."""
    parts = [p for p in namespace.split("/") if p]
    return "/" + "/".join(parts)


class Participant:
    """One rclpy context, node and executor for any number of channels."""

    def __init__(self, node_name: str, domain_id: int | None = None):
        self.context = Context()
        rclpy.init(context=self.context, domain_id=domain_id)
        self.node = rclpy.create_node(node_name, context=self.context,
                                      start_parameter_services=False)
        self.executor = SingleThreadedExecutor(context=self.context)
        self.executor.add_node(self.node)
        self.closed = False

    def spin_for(self, done: Callable[[], object], seconds: float) -> bool:
        """Process incoming messages until `done()` or `seconds` passed; whether it is done."""
        deadline = time.monotonic() + seconds
        while not done():
            remaining = deadline - time.monotonic()
            if remaining <= 0:
                return False
            self.executor.spin_once(timeout_sec=min(remaining, 0.05))
        return True

    def take_for(self, awaited: Callable[[], list], seconds: float, subscriptions) -> bool:
        """`spin_for` for the lockstep hot path: wait on the subscriptions `awaited()` names (those
        whose message of the step has not arrived yet; all of them among `subscriptions`), take
        every message they hold and hand it to the subscription's own callback, until `awaited()`
        is empty (True) or `seconds` passed (False). The executor's general machinery (a wait set
        of every entity, one task object per callback) cost about as much CPU per step as the
        rest of the agent together; nothing else of the node is served meanwhile (service replies
        wait for the next `spin_for`). Each wait holds only what is still awaited: a vector env of
        64 environments rebuilt a wait set of all 192 subscriptions for every message."""
        deadline = time.monotonic() + seconds
        by_pointer = {sub.handle.pointer: sub for sub in subscriptions}
        with contextlib.ExitStack() as handles:
            for sub in subscriptions:
                handles.enter_context(sub.handle)
            wait_set = _rclpy.WaitSet(len(subscriptions), 0, 0, 0, 0, 0, self.context.handle)
            while pending := awaited():
                remaining = deadline - time.monotonic()
                if remaining <= 0:
                    return False
                wait_set.clear_entities()
                for sub in pending:
                    wait_set.add_subscription(sub.handle)
                wait_set.wait(int(min(remaining, 0.05) * 1e9))
                # One message per ready subscription and wait: readiness is "has unread data",
                # so a reader holding more is ready again at once.
                for pointer in wait_set.get_ready_entities("subscription"):
                    sub = by_pointer[pointer]
                    taken = sub.handle.take_message(sub.msg_type, sub.raw)
                    if taken is not None:
                        sub.callback(taken[0])
        return True

    def close(self) -> None:
        if self.closed:
            return
        self.closed = True
        self.executor.shutdown()
        self.node.destroy_node()
        rclpy.shutdown(context=self.context)


@dataclass
class ObservationView:
    """What the Gymnasium envs use of a composuite_msgs/Observation."""

    episode: int
    step: int
    stamp_ns: int
    includes_task: bool
    flat: np.ndarray
    # The task factor's one-hots in the flat vector's order: object, robot, obstacle, objective.
    task_one_hots: np.ndarray

    @classmethod
    def of_message(cls, m: Observation) -> ObservationView:
        t = m.task
        return cls(m.episode, m.step, m.header.stamp.sec * 1_000_000_000 + m.header.stamp.nanosec,
                   m.includes_task, np.asarray(m.flat, dtype=np.float64),
                   np.concatenate([t.object_id, t.robot_id, t.obstacle_id, t.objective_id]))

    @classmethod
    def of_bytes(cls, data: bytes) -> ObservationView:
        v = _OBSERVATION_FIELDS.read(data)
        return cls(v["episode"], v["step"], v["header.stamp.sec"] * 1_000_000_000 + v["header.stamp.nanosec"],
                   v["includes_task"], v["flat"],
                   np.concatenate([v[f"task.{k}"] for k in ("object_id", "robot_id", "obstacle_id", "objective_id")]))


_OBSERVATION_FIELDS = FieldReader(Observation, [
    "header.stamp.sec", "header.stamp.nanosec", "episode", "step", "includes_task", "flat",
    "task.object_id", "task.robot_id", "task.obstacle_id", "task.objective_id"])


def read_fields(message_class):
    """Class decorator for a dataclass whose fields are named as fields of `message_class`:
    gives it `of_bytes(data)`, which fills it from a serialized message (one FieldReader, the
    field list taken from the dataclass itself)."""

    def decorate(view):
        reader = FieldReader(message_class, [f.name for f in dataclass_fields(view)])
        view.of_bytes = classmethod(lambda cls, data: cls(**reader.read(data)))
        return view

    return decorate


@read_fields(StagedReward)
@dataclass
class RewardView:
    """What the Gymnasium envs use of a composuite_msgs/StagedReward."""

    episode: int
    step: int
    stage_names: list[str]
    stage_values: np.ndarray
    current_stage: int
    total: float
    success: bool


@read_fields(EpisodeStatus)
@dataclass
class StatusView:
    """What the Gymnasium envs use of a composuite_msgs/EpisodeStatus."""

    episode: int
    step: int
    done: bool
    terminated: bool
    truncated: bool
    reason_text: str


@dataclass
class StepMessages:
    """What one lockstep step produced."""

    observation: ObservationView
    reward: RewardView
    status: StatusView


class Channel:
    """One environment of the suite, in `namespace`."""

    def __init__(self, participant: Participant, namespace: str, timeout: float):
        self.participant = participant
        self.namespace = normalize_namespace(namespace)
        self.timeout = timeout
        node = participant.node
        prefix = "" if self.namespace == "/" else self.namespace
        self.observations: dict[tuple[int, int], ObservationView] = {}
        self.rewards: dict[tuple[int, int], RewardView] = {}
        self.statuses: dict[tuple[int, int], StatusView] = {}
        # The latched URDF of each robot seen, by its <robot name> (`iiwa`, `gen3`, ...).
        self.robot_descriptions: dict[str, str] = {}
        # No QoS event handlers: each is one more entity in every wait of the lockstep loop, and
        # rclpy's default ones only log incompatible QoS, which cannot happen with these profiles.
        no_sub_events = SubscriptionEventCallbacks(use_default_callbacks=False)
        no_pub_events = PublisherEventCallbacks(use_default_callbacks=False)
        self._prefix = prefix
        self.subscriptions = {
            # Raw: only the fields an agent uses are read (see _cdr.py); every step brings one of
            # each, and rclpy's conversion builds every nested message as Python objects.
            "observation": node.create_subscription(
                Observation, f"{prefix}/observation", self._on_observation, STATE_QOS,
                event_callbacks=no_sub_events, raw=True),
            "reward": node.create_subscription(
                StagedReward, f"{prefix}/reward", self._on_reward, STATE_QOS,
                event_callbacks=no_sub_events, raw=True),
            "episode": node.create_subscription(
                EpisodeStatus, f"{prefix}/episode", self._on_status, STATE_QOS,
                event_callbacks=no_sub_events, raw=True),
        }
        self.description = None  # robot_description, subscribed when first needed
        # Stamped, so the sim drops an action sent for an earlier episode.
        self.reference_action = node.create_publisher(
            ReferenceAction, f"{prefix}/reference_action_stamped", STATE_QOS,
            event_callbacks=no_pub_events)
        self.joint_command = node.create_publisher(
            JointState, f"{prefix}/joint_command", STATE_QOS, event_callbacks=no_pub_events)
        self.reset_client = node.create_client(Reset, f"{prefix}/reset")
        self.set_task_client = node.create_client(SetTask, f"{prefix}/set_task")
        self.sample_tasks_client = node.create_client(SampleTasks, f"{prefix}/sample_tasks")
        self.episode = 0
        self.step_count = 0
        # The stamp (sim time, ns) of the latest observation taken: commands carry it, so the
        # sim drops one that arrives after another episode began.
        self.answered_ns = 0

    # ---- incoming ---------------------------------------------------------------------------

    def _on_observation(self, data: bytes) -> None:
        message = ObservationView.of_bytes(data)
        if message.episode >= self.episode:
            self.observations[(message.episode, message.step)] = message

    def _on_reward(self, data: bytes) -> None:
        message = RewardView.of_bytes(data)
        if message.episode >= self.episode:
            self.rewards[(message.episode, message.step)] = message

    def _on_status(self, data: bytes) -> None:
        message = StatusView.of_bytes(data)
        if message.episode >= self.episode:
            self.statuses[(message.episode, message.step)] = message

    def _on_description(self, message: String) -> None:
        try:
            name = ElementTree.fromstring(message.data).get("name", "")
        except ElementTree.ParseError:
            return
        self.robot_descriptions[name.lower()] = message.data

    # ---- readiness --------------------------------------------------------------------------

    def missing(self) -> list[str]:
        """What this channel still waits for before it can reset and step."""
        missing = []
        for subscription in self.subscriptions.values():
            if subscription.get_publisher_count() == 0:
                missing.append(f"a publisher of {subscription.topic_name}")
        for client in (self.reset_client, self.set_task_client):
            if not client.service_is_ready():
                missing.append(f"the {client.srv_name} service")
        if (self.reference_action.get_subscription_count() == 0
                or self.joint_command.get_subscription_count() == 0):
            missing.append(f"the sim's command readers in {self.namespace}")
        return missing

    @property
    def discovery_timeout(self) -> float:
        return DISCOVERY_TIMEOUT_FACTOR * self.timeout

    def not_running_error(self, waited_for: str, seconds: float | None = None) -> SuiteNotRunningError:
        missing = self.missing()
        return SuiteNotRunningError(
            f"no CompoSuite-ROS environment answered in namespace {self.namespace} within "
            f"{seconds or self.timeout:g} s ({waited_for}; still missing: {', '.join(missing) or 'nothing'}). "
            "Is `composuite launch` running there, in lockstep mode, with the same ROS_DOMAIN_ID?")

    # ---- services ---------------------------------------------------------------------------

    def call(self, client, request, what: str):
        """A service call with resends (see ATTEMPT_BUDGETS_S) until `timeout`."""
        deadline = time.monotonic() + self.timeout
        if not self.participant.spin_for(client.service_is_ready, self.discovery_timeout):
            raise self.not_running_error(f"waiting for {client.srv_name}", self.discovery_timeout)
        for attempt in itertools.count():
            future = client.call_async(request)
            budget = min(attempt_budget(attempt), max(deadline - time.monotonic(), 0.0))
            if self.participant.spin_for(future.done, budget):
                return future.result()
            client.remove_pending_request(future)
            if time.monotonic() >= deadline:
                raise self.not_running_error(f"no reply to {what}")

    def set_task(self, task: Task) -> Task:
        """Set `task`; the task as the suite spells it (its wire names)."""
        reply = self.call(self.set_task_client,
                          SetTask.Request(robot=task.robot, object=task.object, obstacle=task.obstacle,
                                          objective=task.objective),
                          f"set_task {task}")
        if not reply.success:
            raise ValueError(f"set_task {task} refused in {self.namespace}: {reply.message}")
        return Task.of_spec(reply.task)

    def sample_tasks(self, experiment: str, num_train: int, element: str, seed: int,
                     no_shuffle: bool = False) -> tuple[list[Task], list[Task]]:
        reply = self.call(self.sample_tasks_client,
                          SampleTasks.Request(experiment=experiment, num_train=num_train,
                                              element=element, seed=seed, no_shuffle=no_shuffle),
                          "sample_tasks")
        if not reply.success:
            raise ValueError(f"sample_tasks refused: {reply.message}")
        return [Task.of_spec(t) for t in reply.train], [Task.of_spec(t) for t in reply.test]

    # ---- episodes ---------------------------------------------------------------------------

    def wait_ready(self) -> None:
        if not self.participant.spin_for(lambda: not self.missing(), self.discovery_timeout):
            raise self.not_running_error("waiting for the suite's topics and services", self.discovery_timeout)

    def start_reset(self, seed: int):
        """Send a reset request; returns the future."""
        return self.reset_client.call_async(Reset.Request(seed=seed, use_seed=True))

    def reset(self, seed: int) -> Reset.Response:
        """Start an episode with `seed`; returns the reply (step-0 observation inside).

        A reset is asked again (same seed: the same start) when its reply or its step-0
        observation does not arrive, which only happens while discovery is still settling; for at
        most the discovery timeout."""
        self.wait_ready()
        deadline = time.monotonic() + self.discovery_timeout
        for attempt in itertools.count():
            future = self.start_reset(seed)
            if not self.participant.spin_for(future.done, min(self.timeout, attempt_budget(attempt))):
                self.reset_client.remove_pending_request(future)
            else:
                reply = self.finish_reset(future)
                if self.await_step0():
                    return reply
            if time.monotonic() >= deadline:
                raise self.not_running_error(
                    f"no reset reply with its step-0 observation after {attempt + 1} attempts",
                    self.discovery_timeout)

    def finish_reset(self, future) -> Reset.Response:
        reply = future.result()
        if not reply.success:
            raise RuntimeError(f"reset refused in {self.namespace}: {reply.message}")
        self.episode, self.step_count = reply.episode, 0
        stamp = reply.observation.header.stamp
        self.answered_ns = stamp.sec * 1_000_000_000 + stamp.nanosec
        # Drop what belongs to earlier episodes; keep what of this one may have come first.
        for store in (self.observations, self.rewards, self.statuses):
            for key in [k for k in store if k[0] != reply.episode]:
                del store[key]
        return reply

    def await_step0(self) -> bool:
        """After a reset reply: whether the episode's step-0 observation, reward and status all
        came (so the three writers know this participant's readers); they are dropped then."""
        if not self.participant.spin_for(self.step0_arrived, STEP0_WAIT_S):
            return False
        for store in (self.observations, self.rewards, self.statuses):
            del store[(self.episode, 0)]
        return True

    def step0_arrived(self) -> bool:
        key = (self.episode, 0)
        return key in self.observations and key in self.rewards and key in self.statuses

    def answered_header(self) -> Header:
        """A header stamped with the observation the next command answers."""
        return Header(stamp=Time(sec=self.answered_ns // 1_000_000_000,
                                 nanosec=self.answered_ns % 1_000_000_000))

    def send_reference_action(self, action) -> None:
        self.reference_action.publish(ReferenceAction(header=self.answered_header(),
                                                      action=[float(a) for a in action]))

    def send_joint_targets(self, names: list[str], positions) -> None:
        self.joint_command.publish(JointState(header=self.answered_header(), name=names,
                                              position=[float(p) for p in positions]))

    def next_key(self) -> tuple[int, int]:
        return (self.episode, self.step_count + 1)

    def step_subscriptions(self) -> list:
        """What a lockstep step's messages arrive on (for `Participant.take_for`)."""
        return list(self.subscriptions.values())

    def step_arrived(self) -> bool:
        key = self.next_key()
        return key in self.observations and key in self.rewards and key in self.statuses

    def step_awaited(self) -> list:
        """The step subscriptions whose message of the next step has not arrived yet."""
        key = self.next_key()
        return [self.subscriptions[name] for name, store in (
            ("observation", self.observations), ("reward", self.rewards), ("episode", self.statuses))
            if key not in store]

    def take_step(self) -> StepMessages:
        key = self.next_key()
        self.step_count += 1
        messages = StepMessages(self.observations.pop(key), self.rewards.pop(key), self.statuses.pop(key))
        self.answered_ns = messages.observation.stamp_ns
        return messages

    def step_lost_error(self) -> StepLostError:
        key = self.next_key()
        got = [name for name, store in (("observation", self.observations), ("reward", self.rewards),
                                        ("episode", self.statuses)) if key in store]
        return StepLostError(
            f"step {key[1]} of episode {key[0]} in {self.namespace} was lost: "
            f"{'got ' + ', '.join(got) if got else 'got nothing'} within {self.timeout:g} s "
            "(observation, reward and episode expected); reset to go on")

    # ---- the robot ----------------------------------------------------------------------------

    def joint_limits(self, robot: str) -> list[tuple[str, float, float]]:
        """(name, lower, upper) of `robot`'s 7 arm joints then its left finger joint, from the
        latched `robot_description` URDF the sim publishes when the robot changes."""
        key = robot.lower()
        if self.description is None:
            self.description = self.participant.node.create_subscription(
                String, f"{self._prefix}/robot_description", self._on_description, LATCHED_QOS)
        if not self.participant.spin_for(lambda: key in self.robot_descriptions, self.timeout):
            raise self.not_running_error(f"waiting for robot_description of {robot}")
        return urdf_joint_limits(self.robot_descriptions[key])


def urdf_joint_limits(urdf: str) -> list[tuple[str, float, float]]:
    """The movable joints of a URDF in document order (revolute arm joints, then the finger
    joints), first 7 revolute and the first prismatic, with their limits."""
    root = ElementTree.fromstring(urdf)
    revolute, prismatic = [], []
    for joint in root.iter("joint"):
        kind = joint.get("type")
        limit = joint.find("limit")
        lower = float(limit.get("lower", -math.inf)) if limit is not None else -math.inf
        upper = float(limit.get("upper", math.inf)) if limit is not None else math.inf
        if kind == "continuous":
            lower, upper = -math.inf, math.inf
        if kind in ("revolute", "continuous"):
            revolute.append((joint.get("name"), lower, upper))
        elif kind == "prismatic":
            prismatic.append((joint.get("name"), lower, upper))
    if len(revolute) != ARM_JOINTS or not prismatic:
        raise RuntimeError(f"robot_description has {len(revolute)} revolute and {len(prismatic)} "
                           f"prismatic joints; expected {ARM_JOINTS} and at least 1")
    return revolute + prismatic[:1]
