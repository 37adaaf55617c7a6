"""ros2_control's interfaces on the sim, driven by the user's own client: real rclpy (ROS 2 Jazzy,
Fast DDS) with `rclpy.action.ActionClient`, and control_msgs / controller_manager_msgs built with
colcon (`msgs/ros2_control`).

- the graph shows both actions with their types; `controller_manager`'s list services answer as
  `ros2 control list_controllers` / `list_hardware_interfaces` expect;
- FollowJointTrajectory: feedback arrives, the result is SUCCESSFUL, the arm ends within
  tolerance; in lockstep the goal advances the sim one period per waypoint, and the observations
  are bit-identical to the same targets sent as `joint_command` (the in-process Env replay);
- a goal naming an unknown joint is rejected, and the log says why;
- a new goal preempts the running one (ABORTED, as joint_trajectory_controller words it); cancel
  ends a goal CANCELED;
- GripperCommand: closing on the box stalls (ABORTED, stalled), closing on nothing reaches;
- forward_position_controller/commands: one lockstep period per command, bit-identical to
  joint_command; a wrong-length command is refused with the reason.

Only run inside scripts/netns-isolate."""

from __future__ import annotations

import math
import time

import pytest
from action_msgs.msg import GoalStatus
from builtin_interfaces.msg import Duration
from composuite_msgs.msg import Observation, Scene, StagedReward, WorldState
from composuite_msgs.srv import Reset, SetTask
from control_msgs.action import FollowJointTrajectory, GripperCommand
from control_msgs.msg import GripperCommand as GripperCommandMsg
from controller_manager_msgs.srv import ListControllers, ListHardwareInterfaces
from rcl_interfaces.msg import Log
from rclpy.action import ActionClient, get_action_names_and_types
from rclpy.qos import DurabilityPolicy, QoSProfile, ReliabilityPolicy
from sensor_msgs.msg import JointState
from std_msgs.msg import Float64MultiArray
from trajectory_msgs.msg import JointTrajectoryPoint

import node_suite
from node_suite import env_replay_expert, env_replay_run, float_bits, ns_of
from rclpy_agent import RclpyAgent

NS = "/rc"
TASK = "IIWA/box/none/pick_place"
PERIOD_NS = 50_000_000
TRAJECTORY_ACTION = f"{NS}/joint_trajectory_controller/follow_joint_trajectory"
GRIPPER_ACTION = f"{NS}/gripper_action_controller/gripper_cmd"
FORWARD = f"{NS}/forward_position_controller/commands"
# The scene's QoS: reliable, transient local, keep last 1 (a late joiner gets the current one).
LATCHED = QoSProfile(depth=1, reliability=ReliabilityPolicy.RELIABLE,
                     durability=DurabilityPolicy.TRANSIENT_LOCAL)
# The left finger joint's closed limit (m): the gripper's "close".
FINGER_CLOSED = -0.0115


@pytest.fixture(scope="module")
def domain() -> int:
    return node_suite.random_domain()


@pytest.fixture(scope="module")
def suite(tmp_path_factory, domain):
    with node_suite.running(tmp_path_factory.mktemp("ros2_control_logs"), NS, domain) as s:
        yield s


@pytest.fixture(autouse=True)
def show_logs_on_failure(suite):
    yield
    print(suite.all_stderr())


class Cell:
    """The agent's view of one arm: reset, joint_command, observations, and the controllers."""

    def __init__(self, agent: RclpyAgent):
        self.agent = agent
        node = agent.node
        self.observations: dict[tuple[int, int], Observation] = {}
        self.states: list[JointState] = []
        node.create_subscription(Observation, f"{NS}/observation",
                                 lambda m: self.observations.__setitem__((m.episode, m.step), m), 100)
        node.create_subscription(JointState, f"{NS}/joint_states", self.states.append, 100)
        self.world_states: dict[tuple[int, int], WorldState] = {}
        self.rewards: dict[tuple[int, int], StagedReward] = {}
        self.scenes: list[Scene] = []
        node.create_subscription(WorldState, f"{NS}/world_state",
                                 lambda m: self.world_states.__setitem__((m.episode, m.step), m), 100)
        node.create_subscription(StagedReward, f"{NS}/reward",
                                 lambda m: self.rewards.__setitem__((m.episode, m.step), m), 100)
        node.create_subscription(Scene, f"{NS}/scene", self.scenes.append, LATCHED)
        self.gripper_command = node.create_publisher(GripperCommandMsg, f"{NS}/gripper_command", 10)
        self.command = node.create_publisher(JointState, f"{NS}/joint_command", 10)
        self.forward = node.create_publisher(Float64MultiArray, FORWARD, 10)
        self.set_task = node.create_client(SetTask, f"{NS}/set_task")
        self.reset_client = node.create_client(Reset, f"{NS}/reset")
        self.trajectory = ActionClient(node, FollowJointTrajectory, TRAJECTORY_ACTION)
        self.gripper = ActionClient(node, GripperCommand, GRIPPER_ACTION)
        self.episode = 0
        self.arm: list[str] = []

    def connect(self) -> None:
        """Wait until every endpoint is matched and every topic has delivered once (a volatile
        sample sent before the match is lost: reset and step until all arrive)."""
        agent = self.agent
        assert self.trajectory.wait_for_server(timeout_sec=20.0), "no trajectory action server"
        assert self.gripper.wait_for_server(timeout_sec=20.0), "no gripper action server"
        agent.spin_until(lambda: self.command.get_subscription_count() >= 1
                         and self.forward.get_subscription_count() >= 1
                         and agent.node.count_publishers(f"{NS}/observation") >= 1,
                         what="joint_command, forward commands and observation to match")
        robot, obj, obstacle, objective = TASK.split("/")
        answer = agent.call(self.set_task, SetTask.Request(robot=robot, object=obj,
                                                           obstacle=obstacle, objective=objective))
        assert answer.success, answer.message
        for _ in range(10):
            start = self.reset(1)
            self.command.publish(JointState(name=self.arm, position=start))
            try:
                agent.spin_until(lambda: (self.episode, 1) in self.observations, 1.0)
                return
            except AssertionError:
                continue
        raise AssertionError("observations never arrived")

    def reset(self, seed: int) -> list[float]:
        """A new episode; the arm's joint positions at its start."""
        reply = self.agent.call(self.reset_client, Reset.Request(seed=seed, use_seed=True))
        assert reply.success, reply.message
        self.episode = reply.episode
        self.observations[(reply.episode, 0)] = reply.observation
        stamp = reply.observation.header.stamp
        state = self.agent.spin_until(
            lambda: next((s for s in self.states if s.header.stamp == stamp), None),
            what="joint_states of the reset")
        self.arm = [n for n in state.name if not n.endswith("finger_joint")]
        return list(state.position[:7])

    def wait_steps(self, last: int) -> list[Observation]:
        """Observations 0..`last` of the current episode."""
        self.agent.spin_until(lambda: all((self.episode, k) in self.observations for k in range(last + 1)),
                              what=f"observations up to step {last}")
        return [self.observations[(self.episode, k)] for k in range(last + 1)]

    def last_step_settled(self, quiet: float = 0.5) -> int:
        """The current episode's last step, once no new step has come for `quiet` s."""
        def last() -> int:
            return max(k for (e, k) in self.observations if e == self.episode)
        seen, since = last(), time.monotonic()
        while time.monotonic() - since < quiet:
            self.agent.executor.spin_once(timeout_sec=0.05)
            if last() != seen:
                seen, since = last(), time.monotonic()
        return seen

    def send(self, client: ActionClient, goal, feedback=None):
        """Send a goal; its handle once the server answered (accepted or not)."""
        future = client.send_goal_async(goal, feedback_callback=feedback)
        self.agent.spin_until(future.done, what="the goal response")
        return future.result()

    def result(self, handle, timeout: float = 30.0):
        """The goal's result. A result request sent before the server's reply writer matched us
        may go unanswered: ask again every few seconds (the server answers every request)."""
        deadline = time.monotonic() + timeout
        while True:
            future = handle.get_result_async()
            try:
                self.agent.spin_until(future.done, min(3.0, max(deadline - time.monotonic(), 0.01)),
                                      "the goal's result")
                return future.result()
            except AssertionError:
                if time.monotonic() >= deadline:
                    raise


@pytest.fixture(scope="module")
def cell(suite, domain):
    agent = RclpyAgent(domain)
    c = Cell(agent)
    c.connect()
    yield c
    agent.close()
    suite.assert_running()


def uuid_bytes(uuid) -> bytes:
    return bytes(int(b) for b in uuid)


def trajectory_goal(names: list[str], points: list[list[float]], period_ns: int = PERIOD_NS):
    """One waypoint per `period_ns`, positions only (linear interpolation between them)."""
    goal = FollowJointTrajectory.Goal()
    goal.trajectory.joint_names = list(names)
    for k, positions in enumerate(points, start=1):
        t = k * period_ns
        goal.trajectory.points.append(JointTrajectoryPoint(
            positions=[float(p) for p in positions],
            time_from_start=Duration(sec=t // 1_000_000_000, nanosec=t % 1_000_000_000)))
    return goal


def sweep(start: list[float], steps: int, size: float = 0.15) -> list[list[float]]:
    """A smooth motion away from `start`, rounded so the values are exact in any encoding."""
    return [[round(q + size * math.sin(math.pi * k / (2 * steps)) * (1 if j % 2 else -1), 6)
             for j, q in enumerate(start)] for k in range(1, steps + 1)]


def test_the_graph_and_the_controller_manager_show_the_controllers(cell):
    agent = cell.agent
    actions = agent.spin_until(
        lambda: (lambda a: a if TRAJECTORY_ACTION in a and GRIPPER_ACTION in a else None)(
            dict(get_action_names_and_types(agent.node))),
        what="both actions in the graph")
    assert actions[TRAJECTORY_ACTION] == ["control_msgs/action/FollowJointTrajectory"]
    assert actions[GRIPPER_ACTION] == ["control_msgs/action/GripperCommand"]

    listing = agent.node.create_client(ListControllers, f"{NS}/controller_manager/list_controllers")
    controllers = {c.name: c for c in agent.call(listing, ListControllers.Request()).controller}
    assert {n: (c.type, c.state) for n, c in controllers.items()} == {
        "joint_state_broadcaster": ("joint_state_broadcaster/JointStateBroadcaster", "active"),
        "joint_trajectory_controller": ("joint_trajectory_controller/JointTrajectoryController", "active"),
        "forward_position_controller": ("position_controllers/JointGroupPositionController", "active"),
        "gripper_action_controller": ("position_controllers/GripperActionController", "active"),
    }
    arm_position = [f"{n}/position" for n in cell.arm]
    assert list(controllers["joint_trajectory_controller"].claimed_interfaces) == arm_position
    assert list(controllers["gripper_action_controller"].claimed_interfaces) == ["l_finger_joint/position"]
    assert all(c.update_rate == 20 for c in controllers.values())

    interfaces = agent.node.create_client(
        ListHardwareInterfaces, f"{NS}/controller_manager/list_hardware_interfaces")
    reply = agent.call(interfaces, ListHardwareInterfaces.Request())
    commands = [i.name for i in reply.command_interfaces]
    assert commands == sorted(arm_position + ["l_finger_joint/position"])
    assert all(i.is_claimed and i.is_available and i.data_type == "double" for i in reply.command_interfaces)
    assert len(reply.state_interfaces) == 16 and not any(i.is_claimed for i in reply.state_interfaces)


def test_a_trajectory_goal_succeeds_with_feedback_bit_identical_to_joint_command(cell):
    seed = 3
    start = cell.reset(seed)
    points = sweep(start, 20)
    feedback = []
    handle = cell.send(cell.trajectory, trajectory_goal(cell.arm, points),
                       lambda m: feedback.append(m.feedback))
    assert handle.accepted
    result = cell.result(handle)
    assert result.status == GoalStatus.STATUS_SUCCEEDED
    assert (result.result.error_code, result.result.error_string) == (
        FollowJointTrajectory.Result.SUCCESSFUL, "Goal successfully reached!")
    # Lockstep: exactly one period per waypoint, then nothing more.
    observations = cell.wait_steps(20)
    assert cell.last_step_settled() == 20
    stamps = [ns_of(o.header.stamp) for o in observations]
    assert [b - a for a, b in zip(stamps, stamps[1:])] == [PERIOD_NS] * 20
    # Feedback in the controller's joint order, stamped in sim time.
    assert feedback, "no feedback arrived"
    assert all(list(f.joint_names) == cell.arm for f in feedback)
    last = feedback[-1]
    assert ns_of(last.header.stamp) in stamps
    assert all(math.isclose(e, d - a, abs_tol=1e-12) for e, d, a in
               zip(last.error.positions, last.desired.positions, last.actual.positions))
    # The arm ends within tolerance of the last waypoint.
    end_stamp = observations[-1].header.stamp
    final = cell.agent.spin_until(
        lambda: next((s.position[:7] for s in cell.states if s.header.stamp == end_stamp), None),
        what="joint_states of the last step")
    assert max(abs(q - p) for q, p in zip(final, points[-1])) < 0.05, (list(final), points[-1])
    # The same targets as joint_command (the in-process Env, which joint_command matches bit
    # for bit): the same observations, bit for bit.
    replay = env_replay_run({"task": TASK, "seed": seed,
                             "commands": [{"joints": p, "gripper": None} for p in points]})
    assert [float_bits(o.flat) for o in observations] == [float_bits(r["flat"]) for r in replay]


def test_a_goal_naming_an_unknown_joint_is_rejected_and_the_log_says_why(cell, suite):
    start = cell.reset(4)
    names = list(cell.arm)
    names[2] = "elbow"
    logs: list = []
    cell.agent.node.create_subscription(
        Log, "/rosout", logs.append,
        QoSProfile(depth=100, reliability=ReliabilityPolicy.RELIABLE, durability=DurabilityPolicy.VOLATILE))
    since = len(suite.stderr("sim"))
    handle = cell.send(cell.trajectory, trajectory_goal(names, [start]))
    assert not handle.accepted
    reason = "goal rejected: Incoming joint elbow doesn't match the controller's joints"
    suite.wait_for_log("sim", reason, since=since)

    # The reason reaches a ROS user on /rosout (`ros2 topic echo /rosout`, rqt_console): offer
    # the bad goal until the rosout subscription has matched too.
    def warned():
        if not any(reason in m.msg for m in logs):
            assert not cell.send(cell.trajectory, trajectory_goal(names, [start])).accepted
            cell.agent.executor.spin_once(timeout_sec=0.1)
        return [m for m in logs if reason in m.msg]
    record = cell.agent.spin_until(warned, what="the rejection on /rosout")[0]
    assert record.level == Log.WARN and record.name == f"{NS.strip('/')}.sim"


def test_a_new_goal_preempts_the_running_one_and_cancel_ends_a_goal(cell):
    start = cell.reset(5)
    # 400 periods (20 s of sim time): still running when the next goal arrives.
    feedback_first = []
    first = cell.send(cell.trajectory, trajectory_goal(cell.arm, sweep(start, 400, 0.1)),
                      lambda m: feedback_first.append(m))
    assert first.accepted
    cell.agent.spin_until(lambda: feedback_first, what="feedback of the first goal")
    feedback_second = []
    second = cell.send(cell.trajectory, trajectory_goal(cell.arm, sweep(start, 400, -0.1)),
                       lambda m: feedback_second.append(m))
    assert second.accepted
    preempted = cell.result(first)
    assert preempted.status == GoalStatus.STATUS_ABORTED
    assert (preempted.result.error_code, preempted.result.error_string) == (
        FollowJointTrajectory.Result.INVALID_GOAL, "Current goal preempted by new incoming action.")
    cell.agent.spin_until(lambda: feedback_second, what="feedback of the second goal")
    cancel = second.cancel_goal_async()
    cell.agent.spin_until(cancel.done, what="the cancel response")
    assert [uuid_bytes(g.goal_id.uuid) for g in cancel.result().goals_canceling] == [
        uuid_bytes(second.goal_id.uuid)]
    canceled = cell.result(second)
    assert canceled.status == GoalStatus.STATUS_CANCELED
    # Both ended early, and with no goal running the sim stands still (lockstep).
    last = cell.last_step_settled()
    assert last < 400
    time.sleep(0.3)
    assert cell.last_step_settled() == last


def test_the_gripper_stalls_on_the_box_and_reaches_without_it(cell):
    expert = env_replay_expert(TASK, 0)
    # The expert closes the gripper at this step, the box between its open fingers.
    close_step = next(k for k, c in enumerate(expert["commands"])
                      if c["gripper"] != expert["commands"][0]["gripper"])
    cell.reset(0)  # the fingers start open, as the expert's first command keeps them
    for k, c in enumerate(expert["commands"][:close_step], start=1):
        cell.command.publish(JointState(name=cell.arm, position=c["joints"]))
        cell.wait_steps(k)
    goal = GripperCommand.Goal()
    goal.command.position = FINGER_CLOSED
    goal.command.max_effort = 20.0
    handle = cell.send(cell.gripper, goal)
    assert handle.accepted
    stalled = cell.result(handle)
    assert stalled.status == GoalStatus.STATUS_ABORTED
    assert stalled.result.stalled and not stalled.result.reached_goal
    assert stalled.result.position > FINGER_CLOSED + 0.01  # held open by the box
    assert stalled.result.effort == 20.0

    cell.reset(0)  # the box back on the table, the fingers open above nothing
    handle = cell.send(cell.gripper, goal)
    reached = cell.result(handle)
    assert reached.status == GoalStatus.STATUS_SUCCEEDED
    assert reached.result.reached_goal and not reached.result.stalled
    assert abs(reached.result.position - FINGER_CLOSED) < 0.01


def test_forward_commands_step_like_joint_command_and_bad_ones_are_refused(cell, suite):
    seed = 6
    start = cell.reset(seed)
    since = len(suite.stderr("sim"))
    cell.forward.publish(Float64MultiArray(data=start[:6]))
    suite.wait_for_log("sim", "forward_position_controller/commands refused: arm command has 6 values",
                       since=since)
    points = sweep(start, 10)
    for k, p in enumerate(points, start=1):
        cell.forward.publish(Float64MultiArray(data=p))
        cell.wait_steps(k)
    observations = cell.wait_steps(10)
    replay = env_replay_run({"task": TASK, "seed": seed,
                             "commands": [{"joints": p, "gripper": None} for p in points]})
    assert [float_bits(o.flat) for o in observations] == [float_bits(r["flat"]) for r in replay]


def test_a_real_cell_world_state_from_outside_drives_the_reward_node_alone(cell, tmp_path, domain):
    """A real arm's cell has no sim: the arm's driver offers the controllers, and the object's pose
    comes from mocap or perception into `world_state`. Here an outside publisher (this test)
    plays the world states of a real episode — the expert's, recorded from the sim — to a reward
    node running alone, with the scene it belongs to: the rewards and success are the sim's own,
    bit for bit."""
    expert = env_replay_expert(TASK, 0)
    success_step = expert["success_step"]
    cell.reset(0)
    episode = cell.episode
    held = expert["commands"][0]["gripper"]
    for k, c in enumerate(expert["commands"][:success_step], start=1):
        if c["gripper"] is not None and c["gripper"] != held:
            held = c["gripper"]
            cell.gripper_command.publish(GripperCommandMsg(position=held[0], max_effort=held[1]))
        cell.command.publish(JointState(name=cell.arm, position=c["joints"]))
        cell.agent.spin_until(lambda: (episode, k) in cell.rewards and (episode, k) in cell.world_states,
                              what=f"reward and world_state of step {k}")
    recorded = [cell.world_states[(episode, k)] for k in range(1, success_step + 1)]
    sim_rewards = [cell.rewards[(episode, k)] for k in range(1, success_step + 1)]
    assert sim_rewards[-1].success, "the expert's episode should succeed at its success step"
    scene = cell.agent.spin_until(lambda: next((m for m in reversed(cell.scenes) if m.episode == episode), None),
                                  what="the episode's scene")

    with node_suite.running(tmp_path, "/cell", domain, nodes=("reward",)) as alone:
        node = cell.agent.node
        scene_pub = node.create_publisher(Scene, "/cell/scene", LATCHED)
        world_pub = node.create_publisher(WorldState, "/cell/world_state", 10)
        rewards: dict[int, StagedReward] = {}
        node.create_subscription(StagedReward, "/cell/reward", lambda m: rewards.__setitem__(m.step, m), 100)
        cell.agent.spin_until(lambda: world_pub.get_subscription_count() >= 1
                              and scene_pub.get_subscription_count() >= 1
                              and node.count_publishers("/cell/reward") >= 1,
                              what="the lone reward node to match")
        scene_pub.publish(scene)
        # Volatile topics: offer the first world state until its reward comes back (matched both ways).
        cell.agent.spin_until(lambda: rewards.get(1) or world_pub.publish(recorded[0]), what="the first reward")
        for w in recorded[1:]:
            world_pub.publish(w)
            cell.agent.spin_until(lambda: w.step in rewards, what=f"the reward of step {w.step}")
        alone.assert_running()
    cell_rewards = [rewards[k] for k in range(1, success_step + 1)]
    assert float_bits(r.total for r in cell_rewards) == float_bits(r.total for r in sim_rewards)
    assert [list(r.stage_values) for r in cell_rewards] == [list(r.stage_values) for r in sim_rewards]
    assert [r.success for r in cell_rewards] == [r.success for r in sim_rewards]
    assert [ns_of(r.header.stamp) for r in cell_rewards] == [ns_of(w.header.stamp) for w in recorded]
