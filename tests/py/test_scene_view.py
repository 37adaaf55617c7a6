"""A recorded session shows the scene with nothing else running: judged from the bag alone by
readers nobody here wrote (`rosbags` decodes it, the URDF is parsed with the standard library's
XML parser, the kinematics are numpy).

- TF: at every recorded step (every sim time stamp on `tf`) every link frame of the
  `robot_description` in force resolves to `world` through `tf` + `tf_static`; each link's
  transform is what robot_state_publisher would compute from the URDF and that step's
  `joint_states`; the composed grip site and hand equal the recorded `eef` frame and
  `world_state`'s eef pose.
- Markers: `scene_markers` holds the arena of the recorded `scene` (DELETEALL first, then every
  part but the object's, with its shape, size and pose), latched; `object_markers` follows the
  recorded object pose at every step.

The session changes the arm (IIWA, then Jaco: both have `link_1`…`link_7` and `right_hand`, with
other roots and offsets), so it also covers a task change. Only run inside scripts/netns-isolate."""

from __future__ import annotations

import xml.etree.ElementTree as ET
from dataclasses import dataclass

import numpy as np
import pytest
import yaml

from node_suite import ns_of
from test_recorder import bag_messages
from test_session import session

TASKS = ["IIWA/dumbbell/object_wall/shelf", "Jaco/hollow_box/goal_wall/trash_can"]
HORIZON = 15
WORLD = "world"
# The sim's own frames on `tf` besides the URDF links.
SIM_FRAMES = {"eef", "object", "goal"}
# robot_state_publisher would compute the transforms by forward kinematics from joint_states; the
# sim takes them from its f32 physics, which agrees with FK to ~1e-6 m.
FK_TOLERANCE_M, FK_TOLERANCE_RAD = 1e-5, 1e-4
# Composing the published transforms gives the sim's own poses to rounding.
COMPOSED_TOLERANCE = 1e-6
# composuite_msgs/ScenePart.SHAPE_CYLINDER; visualization_msgs/Marker's CUBE, CYLINDER, ADD, DELETEALL.
SHAPE_CYLINDER = 2
CUBE, CYLINDER, ADD, DELETEALL = 1, 3, 0, 3


# ---- a URDF and rigid transforms, independently of the suite's code -----------------------------


@dataclass
class Joint:
    name: str
    kind: str
    parent: str
    child: str
    origin: np.ndarray  # 4x4
    axis: np.ndarray


@dataclass
class Urdf:
    root: str
    links: list[str]
    joints: dict[str, Joint]  # by child link


def rpy_matrix(roll: float, pitch: float, yaw: float) -> np.ndarray:
    """URDF's fixed-axis roll, pitch, yaw: R = Rz(yaw) Ry(pitch) Rx(roll)."""
    cr, sr, cp, sp, cy, sy = np.cos(roll), np.sin(roll), np.cos(pitch), np.sin(pitch), np.cos(yaw), np.sin(yaw)
    rx = np.array([[1, 0, 0], [0, cr, -sr], [0, sr, cr]])
    ry = np.array([[cp, 0, sp], [0, 1, 0], [-sp, 0, cp]])
    rz = np.array([[cy, -sy, 0], [sy, cy, 0], [0, 0, 1]])
    return rz @ ry @ rx


def homogeneous(rotation: np.ndarray, translation) -> np.ndarray:
    t = np.eye(4)
    t[:3, :3], t[:3, 3] = rotation, translation
    return t


def axis_angle(axis: np.ndarray, angle: float) -> np.ndarray:
    k = axis / np.linalg.norm(axis)
    skew = np.array([[0, -k[2], k[1]], [k[2], 0, -k[0]], [-k[1], k[0], 0]])
    return np.eye(3) + np.sin(angle) * skew + (1 - np.cos(angle)) * skew @ skew


def quaternion_matrix(q) -> np.ndarray:
    """From a geometry_msgs quaternion (x, y, z, w), normalised as tf2 does."""
    x, y, z, w = np.array([q.x, q.y, q.z, q.w]) / np.linalg.norm([q.x, q.y, q.z, q.w])
    return np.array([
        [1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
        [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
        [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)],
    ])


def transform_matrix(t) -> np.ndarray:
    """A geometry_msgs/Transform as a 4x4 matrix."""
    return homogeneous(quaternion_matrix(t.rotation), [t.translation.x, t.translation.y, t.translation.z])


def pose_matrix(p) -> np.ndarray:
    return homogeneous(quaternion_matrix(p.orientation), [p.position.x, p.position.y, p.position.z])


def pose_tuple(p) -> tuple:
    return (p.position.x, p.position.y, p.position.z, p.orientation.x, p.orientation.y, p.orientation.z,
            p.orientation.w)


def rotation_gap(a: np.ndarray, b: np.ndarray) -> float:
    """The angle (rad) of the rotation between two rotation matrices."""
    return float(np.arccos(np.clip((np.trace(a.T @ b) - 1) / 2, -1.0, 1.0)))


def parse_urdf(text: str) -> Urdf:
    robot = ET.fromstring(text)
    links = [link.get("name") for link in robot.findall("link")]
    joints = {}
    for j in robot.findall("joint"):
        origin = j.find("origin")
        xyz = [float(v) for v in (origin.get("xyz", "0 0 0") if origin is not None else "0 0 0").split()]
        rpy = [float(v) for v in (origin.get("rpy", "0 0 0") if origin is not None else "0 0 0").split()]
        axis = j.find("axis")
        joint = Joint(j.get("name"), j.get("type"), j.find("parent").get("link"), j.find("child").get("link"),
                      homogeneous(rpy_matrix(*rpy), xyz),
                      np.array([float(v) for v in (axis.get("xyz") if axis is not None else "1 0 0").split()]))
        assert joint.child not in joints, f"{joint.child} has two parents"
        joints[joint.child] = joint
    (root,) = [link for link in links if link not in joints]
    return Urdf(root, links, joints)


def joint_motion(joint: Joint, q: float) -> np.ndarray:
    """What robot_state_publisher publishes for a joint at position q: origin, then the motion."""
    if joint.kind in ("revolute", "continuous"):
        return joint.origin @ homogeneous(axis_angle(joint.axis, q), [0, 0, 0])
    if joint.kind == "prismatic":
        return joint.origin @ homogeneous(np.eye(3), joint.axis / np.linalg.norm(joint.axis) * q)
    assert joint.kind == "fixed", joint.kind
    return joint.origin


# ---- the session ---------------------------------------------------------------------------------


@pytest.fixture(scope="module")
def recorded(tmp_path_factory):
    out = tmp_path_factory.mktemp("scene_view") / "s"
    result = session("--tasks", *TASKS, "--episodes", "1", "--policy", "random", "--horizon", str(HORIZON),
                     "--seed", "3", "--out", str(out))
    assert result.returncode == 0, result.stderr[-4000:]
    messages = bag_messages(out / "bag")
    by_suffix = {}
    for topic, items in messages.items():
        by_suffix[topic.rsplit("/", 1)[-1]] = [m for _, m in items]
    info = yaml.safe_load((out / "bag" / "metadata.yaml").read_text())["rosbag2_bagfile_information"]
    qos = {t["topic_metadata"]["name"].rsplit("/", 1)[-1]: t["topic_metadata"]["offered_qos_profiles"]
           for t in info["topics_with_message_count"]}
    return by_suffix, qos


def latest_before(stamped: list, stamp: int, key=lambda m: m.header.stamp):
    """The last of `stamped` (in recording order) whose stamp is before `stamp`."""
    earlier = [m for m in stamped if ns_of(key(m)) < stamp]
    assert earlier, f"nothing before {stamp}"
    return earlier[-1]


def test_every_link_resolves_to_world_at_every_recorded_step(recorded):
    topics, _ = recorded
    urdfs = [parse_urdf(m.data) for m in topics["robot_description"]]
    assert {u.root for u in urdfs} == {"link_0", "link_base"}, "IIWA's and Jaco's descriptions"
    statics = [t for m in topics["tf_static"] for t in m.transforms]
    worlds = {ns_of(w.header.stamp): w for w in topics["world_state"]}
    joint_states = {ns_of(j.header.stamp): j for j in topics["joint_states"]}
    # One tf per step and per reset. The launch's own first episode (before the session's first
    # reset) publishes its step 0 while the recorder's readers are still matching, so that one
    # stamp may be in the bag on some of the topics only; from the first stamp on all three, every
    # step is on each.
    tf_stamps = [ns_of(m.transforms[0].header.stamp) for m in topics["tf"]]
    start = min(set(tf_stamps) & set(worlds) & set(joint_states))
    for stamps in (tf_stamps, worlds, joint_states):
        assert len({s for s in stamps if s < start}) <= 1, "only the launch's step 0 may be partial"
    steps = [m for m, s in zip(topics["tf"], tf_stamps) if s >= start]
    assert {s for s in tf_stamps if s >= start} == {s for s in worlds if s >= start} == {
        s for s in joint_states if s >= start}
    assert len(steps) == len({s for s in worlds if s >= start}) >= 2 * (HORIZON + 1)
    checked_links = 0
    for message in steps:
        stamps = {ns_of(t.header.stamp) for t in message.transforms}
        assert len(stamps) == 1, "one step's transforms share its stamp"
        (stamp,) = stamps
        # The arm in force: the one whose root tf_static placed last before this step.
        root = latest_before(statics, stamp).child_frame_id
        urdf = [u for u in urdfs if u.root == root][-1]
        dynamic = {t.child_frame_id: t for t in message.transforms}
        static = {t.child_frame_id: t for t in statics if ns_of(t.header.stamp) < stamp}
        assert set(dynamic) == SIM_FRAMES | (set(urdf.links) - {urdf.root}), "every link but the root, each once"
        assert len(message.transforms) == len(dynamic)
        positions = dict(zip(joint_states[stamp].name, joint_states[stamp].position))
        composed = {}
        for link in urdf.links:
            # Walk up the tree through tf and tf_static until `world`.
            chain, frame, pose = [], link, np.eye(4)
            while frame != WORLD:
                t = dynamic.get(frame) or static.get(frame)
                assert t is not None, f"{link}: frame {frame} has no transform at {stamp}"
                chain.append(frame)
                assert len(chain) <= len(urdf.links) + 1, f"{link}: a cycle {chain}"
                pose = transform_matrix(t.transform) @ pose
                frame = t.header.frame_id
            composed[link] = pose
            if link == urdf.root:
                continue
            # As robot_state_publisher: the URDF parent, the joint's origin and motion.
            joint = urdf.joints[link]
            t = dynamic[link]
            assert t.header.frame_id == joint.parent, link
            expected = joint_motion(joint, positions.get(joint.name, 0.0))
            ours = transform_matrix(t.transform)
            assert np.linalg.norm(ours[:3, 3] - expected[:3, 3]) < FK_TOLERANCE_M, (link, ours, expected)
            assert rotation_gap(ours[:3, :3], expected[:3, :3]) < FK_TOLERANCE_RAD, link
            checked_links += 1
        # The composed grip site (position) and hand (orientation) are the eef frame and the
        # world_state's eef pose.
        eef = transform_matrix(dynamic["eef"].transform)
        assert dynamic["eef"].header.frame_id == WORLD
        world_eef = pose_matrix(worlds[stamp].eef_pose)
        for reference in (eef, world_eef):
            assert np.linalg.norm(composed["grip_site"][:3, 3] - reference[:3, 3]) < COMPOSED_TOLERANCE
            assert rotation_gap(composed["right_hand"][:3, :3], reference[:3, :3]) < COMPOSED_TOLERANCE
    assert checked_links >= 2 * (HORIZON + 1) * 14


def test_the_latched_topics_are_recorded_as_latched(recorded):
    _, qos = recorded
    for topic in ("robot_description", "tf_static", "scene_markers"):
        (profile,) = qos[topic]
        assert (profile["reliability"], profile["durability"]) == ("reliable", "transient_local"), topic
    for topic in ("tf", "object_markers"):
        (profile,) = qos[topic]
        assert profile["durability"] == "volatile", topic


def test_scene_markers_are_the_recorded_arena(recorded):
    topics, _ = recorded
    scenes = topics["scene"]
    arenas = topics["scene_markers"]
    task = lambda s: (s.task.robot, s.task.object, s.task.obstacle, s.task.objective)
    changes = [s for i, s in enumerate(scenes) if i == 0 or task(s) != task(scenes[i - 1])]
    assert len(arenas) == len(changes) == 2, "drawn once per task"
    for markers in arenas:
        first, *parts = markers.markers
        assert first.action == DELETEALL, "DELETEALL first"
        stamp = ns_of(first.header.stamp)
        scene = latest_before(scenes, stamp)
        arena = [(i, p) for i, p in enumerate(scene.parts) if not p.name.startswith("object/")]
        assert [m.id for m in parts] == [i for i, _ in arena]
        groups = set()
        for marker, (_, part) in zip(parts, arena):
            groups.add(marker.ns)
            assert marker.header.frame_id == WORLD and marker.action == ADD
            assert marker.ns == part.name.split("/")[0]
            assert pose_tuple(marker.pose) == pose_tuple(part.pose)
            h = part.half_size
            if part.shape == SHAPE_CYLINDER:
                assert marker.type == CYLINDER and (marker.scale.x, marker.scale.y, marker.scale.z) == (2 * h.x, 2 * h.x, 2 * h.z)
            else:
                assert marker.type == CUBE and (marker.scale.x, marker.scale.y, marker.scale.z) == (2 * h.x, 2 * h.y, 2 * h.z)
            assert marker.color.a > 0
        objective = scene.task.objective
        expected = {"bin1", "bin2", "goal", "obstacle"} | ({"shelf"} if objective == "shelf" else set()) | (
            {"trash_can"} if objective == "trash_can" else set())
        assert groups == expected, (groups, scene.task)


def test_the_object_marker_follows_the_recorded_object(recorded):
    topics, _ = recorded
    scenes = topics["scene"]
    by_stamp = {ns_of(m.markers[-1].header.stamp): m for m in topics["object_markers"]}
    worlds = topics["world_state"]
    assert len(by_stamp) == len(topics["object_markers"]), "one object_markers message per stamp"
    # Every recorded world state has its object markers. The launch's own first episode (before
    # the session's first reset) is published while the recorder's readers are still matching,
    # so its step-0 state may be in the bag on one of the two topics only.
    first_world = min(ns_of(w.header.stamp) for w in worlds)
    unmatched = set(by_stamp) - {ns_of(w.header.stamp) for w in worlds}
    assert all(stamp < first_world for stamp in unmatched), sorted(unmatched)
    assert len(worlds) >= len(by_stamp) - 1
    for world in worlds:
        stamp = ns_of(world.header.stamp)
        markers = by_stamp[stamp].markers
        if world.step == 0:
            assert markers[0].action == DELETEALL, "an episode's first object markers clear the old ones"
            markers = markers[1:]
        scene = latest_before(scenes, stamp)
        # The object's parts in its body frame, from the scene (placed at its start pose).
        start = pose_matrix(scene.object_start_pose)
        parts = [p for p in scene.parts if p.name.startswith("object/")]
        assert [m.ns for m in markers] == ["object"] * len(parts) and [m.id for m in markers] == list(range(len(parts)))
        now = pose_matrix(world.object_pose)
        for marker, part in zip(markers, parts):
            expected = now @ np.linalg.inv(start) @ pose_matrix(part.pose)
            drawn = pose_matrix(marker.pose)
            assert np.linalg.norm(drawn[:3, 3] - expected[:3, 3]) < 1e-9, part.name
            assert rotation_gap(drawn[:3, :3], expected[:3, :3]) < 1e-6, part.name
            assert marker.type == (CYLINDER if part.shape == SHAPE_CYLINDER else CUBE)
    assert {s.task.object for s in scenes} == {"dumbbell", "hollow_box"}
