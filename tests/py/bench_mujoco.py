"""MuJoCo's cost per physics step on a scene as complex as our physics bench, for issue 31
("our physics step at or below MuJoCo's on a scene of the same complexity"). Prints figures,
asserts nothing. Run it through `scripts/bench-mujoco`, which makes its venv (mujoco 4.0.0).

    python tests/py/bench_mujoco.py [--arms iiwa jaco gen3 panda] [--steps 2000] [--repeats 5]
                                    [--core 1] [--seed 1] [--json]

What is measured, per arm: the wall-clock time (time.perf_counter_ns) of --steps control steps,
each `mujoco.mj_step(model, data, nstep=25)` after setting `data.ctrl`, divided by the physics
steps taken: µs per physics step, the best and the median of --repeats runs (each from the same
reset, with the same targets). Beside it, the scene's size as MuJoCo sees it: `model.nv`
(degrees of freedom), the collision geoms, and the mean contacts (`data.ncon`) and constraint
rows (`data.nefc`) after each control step. Printed, not asserted: whether the box rests at its
spawn height (within 1 cm) after settling and after the run, and how closely the arm tracks
(mean |q − target| after each control step, rad; and |q − set point|, see the servos below).
The script pins itself to one core (--core) where the OS allows.

The rig mirrors `nodes/core/benches/physics.rs` (`cargo bench -p composuite_core --bench
physics`, whose "us/step" column is our figure):
- The arm from `urdf/<arm>.urdf` with `urdf/rethink_gripper.urdf` mounted on its `right_hand`
  link (identity pose), the base at `ROBOT_BASE_POSITION`. Links joined by fixed joints are
  merged into one body, their inertials summed, as `physics/robot_model.rs` does: MuJoCo gets
  our 10 arm bodies (the fixed base, 7 links, 2 fingers). A cylinder `N` with spheres `N_end1`,
  `N_end2` is one capsule geom (urdf/README.md). The arm and gripper collide with the bins,
  the ground and the box, never with themselves (ours: one multibody, self-contacts off), by
  contype/conaffinity bits.
- The PickPlace arena without obstacle: bin 1 and bin 2, floors and rims/walls as box geoms;
  the ground a plane (ours: a half-space); the box a free body resting in bin 1 at its spawn
  height. The scene settles for SETTLE_STEPS untimed steps before each run (ours starts timing
  at once; the box is spawned resting either way).
- Each control step, new random targets: the start pose ± the bench's range, clamped into the
  joint limits (`validate_arm_targets`); then 25 physics steps of dt.
- The stiff servos (`ArmGains`): MuJoCo `position` actuators with our kp, and our kd as `kv`,
  force-limited to each joint's effort; gravity fed forward (`gravcomp`, routed through the
  actuators so it counts against the effort limit, as our set-point feed-forward does); our
  armature, joint damping and dry friction (`frictionloss`). Our servos move their set point
  toward the target by at most the joint's velocity limit × dt every physics step; here the set
  point sent moves by at most 25 × that once per control step, so it ends each control step
  where ours does. The targets and set points are drawn before the timed loop (ours draws them
  inside it: nanoseconds per control step).
- The fingers: a position actuator on each (`GripperParams` kp, kd, force limit; dry friction)
  and an equality constraint q_r = −q_l, as our loader couples them; held open.

MuJoCo's options: timestep = our dt, gravity −g, Newton solver with its default iterations and
tolerance, the default (pyramidal) friction cone, default contact softness (solref/solimp) and
margin 0; the `implicitfast` integrator, whose implicit actuator damping is MuJoCo's counterpart
of rapier's implicit joint motors (with the explicit Euler integrator, the fingers' kd, 100 N·s/m
on 30 g, is unstable at 2 ms).

Not mirrored: rapier's 2 mm speculative contacts (MuJoCo's margin is 0), its friction combine
rule (the mean of two colliders' coefficients; MuJoCo takes the larger), our filter that drops
the floor pairs of links that cannot reach it (MuJoCo's bounding-sphere test against the plane
is as cheap), and MuJoCo also compensates the fingers' own weight on the finger joints (0.3 N
against their 20 N).

Every number of the rig is read at start-up from our sources, the URDFs and the Rust constants
named above, so the two benches cannot drift apart; should the Rust text change shape, the
script stops and says what it could not read.
"""

from __future__ import annotations

import argparse
import ast
import json
import math
import os
import re
import statistics
import sys
import time
import xml.etree.ElementTree as ET
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

# Imported in main(): reading the rig from our sources needs no MuJoCo, so the default tests can
# check that it still reads (tests/py/test_bench_rigs.py) without the opt-in venv.
mujoco = None

REPO = Path(__file__).resolve().parents[2]
ARMS = ["iiwa", "jaco", "gen3", "panda"]
# Untimed physics steps after each reset (0.5 s at 2 ms): the box comes to rest.
SETTLE_STEPS = 250

# Collision bits. MuJoCo pairs two geoms when (contype1 & conaffinity2) or (contype2 &
# conaffinity1) is non-zero: the robot pairs with the scene and the box, never with itself.
ROBOT_BITS = 'contype="1" conaffinity="2"'
SCENE_BITS = 'contype="2" conaffinity="1"'
BOX_BITS = 'contype="3" conaffinity="3"'


# --- Reading our rig from the Rust sources ---------------------------------------------------


class RigReadError(RuntimeError):
    pass


def rust_text(relative: str) -> str:
    """A Rust source file of the repository, `//` comments removed."""
    return re.sub(r"//[^\n]*", "", (REPO / relative).read_text())


def sorted_rs(relative_dir: str) -> list[str]:
    """The `.rs` files of a source folder of the repository, relative paths in name order."""
    return sorted(str(p.relative_to(REPO)) for p in (REPO / relative_dir).glob("*.rs"))


def rust_expr(text: str, start: int) -> str:
    """The Rust expression that starts at `text[start:]`: up to the `,` or `;` (or the closing
    bracket of an enclosing list or call) that ends it."""
    depth = 0
    for i in range(start, len(text)):
        c = text[i]
        if c in "([{":
            depth += 1
        elif c in ")]}":
            if depth == 0:
                return text[start:i].strip()
            depth -= 1
        elif c in ",;" and depth == 0:
            return text[start:i].strip()
    raise RigReadError(f"unterminated expression at {text[start:start + 40]!r}")


def evaluate(expr: str, names: dict | None = None):
    """The value of a Rust literal expression: numbers, strings, arrays `[a, b]` and `[x; n]`,
    + − × ÷, `PI`, and the constants in `names` (which may be indexed)."""
    names = {"PI": math.pi, **(names or {})}
    expr = expr.replace("std::f64::consts::", "")
    expr = re.sub(r"\[([^\[\];]+);\s*(\d+)\]", r"([\1] * \2)", expr)  # [x; n] -> [x] * n
    arithmetic = {ast.Add: float.__add__, ast.Sub: float.__sub__, ast.Div: float.__truediv__}

    def value(node):
        match node:
            case ast.Constant():
                return node.value
            case ast.List():
                return [value(e) for e in node.elts]
            case ast.Name() if node.id in names:
                return names[node.id]
            case ast.UnaryOp(op=ast.USub()):
                return -value(node.operand)
            case ast.Subscript():
                return value(node.value)[value(node.slice)]
            case ast.BinOp(op=ast.Mult()):
                return value(node.left) * value(node.right)  # numbers, or [x] * n
            case ast.BinOp() if type(node.op) in arithmetic:
                left, right = float(value(node.left)), float(value(node.right))
                return arithmetic[type(node.op)](left, right)
        raise RigReadError(f"cannot evaluate {ast.unparse(node)!r} in {expr!r}")

    return value(ast.parse(expr, mode="eval").body)


def find(text: str, pattern: str, where: str, start: int = 0) -> re.Match:
    m = re.compile(pattern).search(text, start)
    if m is None:
        raise RigReadError(f"{where}: nothing matches {pattern!r}")
    return m


def const(text: str, name: str, where: str, names: dict | None = None):
    """The value of `const NAME: T = value;`."""
    m = find(text, rf"\bconst\s+{name}\s*:[^=]*=", where)
    return evaluate(rust_expr(text, m.end()), names)


def field_after(text: str, anchor: str, name: str, where: str, raw: bool = False):
    """The value of the first struct field `name: value` after `anchor` (its text if `raw`)."""
    start = find(text, re.escape(anchor), where).end()
    m = find(text, rf"\b{name}\s*:", f"{where}, after {anchor!r}", start)
    expr = rust_expr(text, m.end())
    return expr if raw else evaluate(expr)


def match_arm(text: str, anchor: str, variant: str, where: str):
    """The value of the arm naming `Robot::<variant>` in the first `match` after `anchor`."""
    start = find(text, re.escape(anchor), where).end()
    for m in re.finditer(r"((?:Robot::\w+\s*\|\s*)*Robot::\w+)\s*=>", text[start:]):
        if f"Robot::{variant}" in re.findall(r"Robot::\w+", m.group(1)):
            return evaluate(rust_expr(text, start + m.end()))
    raise RigReadError(f"{where}, after {anchor!r}: no match arm for Robot::{variant}")


def call_args(text: str, start: int) -> list[str]:
    """The arguments (as text) of the call whose `(` ends at `start`."""
    args, i = [], start
    while True:
        expr = rust_expr(text, i)
        args.append(expr)
        i = text.index(expr, i) + len(expr)
        while text[i].isspace():
            i += 1
        if text[i] == ")":
            return args
        i += 1  # past the comma


@dataclass
class Part:
    """A box: centre and half-extents (m)."""

    name: str
    centre: list[float]
    half: list[float]


@dataclass
class Rig:
    """What our physics bench builds, as read from the sources."""

    dt: float
    substeps: int  # physics steps per control step
    gravity: float
    target_range: tuple[float, float]  # random target offsets from the start pose (rad)
    base_position: list[float]
    mount_link: str  # the arm link the gripper is mounted on (identity pose)
    gripper_root: str
    finger_joints: list[str]  # left, right
    finger_open: float  # left finger position at reset (m)
    finger_coupling: float  # q_right = finger_coupling × q_left
    finger_gains: dict  # kp, kd, max_force, frictionloss
    arm_friction: float  # sliding friction of the arm's colliders
    gripper_friction: float  # of the gripper's (base, fingers, pads)
    table_friction: list[float]  # MuJoCo's three coefficients, every bin geom
    arena: list[Part]
    box: Part  # at its spawn pose
    box_mass: float
    box_condim: int
    box_friction: list[float]
    arms: dict = field(default_factory=dict)  # arm -> start pose and ArmGains


def read_rig(arms: list[str]) -> Rig:
    core = "nodes/core/src"
    params = rust_text(f"{core}/physics/params.rs")
    # SimWorld is split by job over physics/world/*.rs; what is read here may sit in any of them.
    world = "\n".join(rust_text(path) for path in sorted_rs(f"{core}/physics/world"))
    robot_model = rust_text(f"{core}/physics/robot_model.rs")
    robot = rust_text(f"{core}/axes/robot.rs")
    bins = rust_text(f"{core}/arena/bins.rs")
    layouts = rust_text(f"{core}/arena/objective_arena.rs")
    obstacles = rust_text(f"{core}/arena/obstacles.rs")
    fixtures = rust_text(f"{core}/arena/fixtures.rs")
    primitive = rust_text(f"{core}/arena/primitive.rs")
    objects = rust_text(f"{core}/arena/objects.rs")
    bench = rust_text("nodes/core/benches/physics.rs")

    physics = "impl Default for PhysicsParams"
    gripper = "impl Default for GripperParams"
    target_range = find(bench, r"random_range\(\s*(-?[\d.]+)\s*\.\.\s*(-?[\d.]+)\s*\)", "bench")
    # insert_arm(): the arm's colliders have one friction, the gripper's another.
    frictions = find(
        world,
        r"matches!\(tag, ColliderTag::Arm\(_\)\)\s*\{\s*([\d.]+)\s*\}\s*else\s*\{\s*([\d.]+)\s*\}",
        "physics/world/",
    )

    # The PickPlace arena without obstacle: bin 1 and bin 2 only.
    pick_place = "const PICK_PLACE: ObjectiveArena"
    for text, anchor, name in [
        (layouts, pick_place, "fixture_parts"),
        (obstacles, "const NO_OBSTACLE: ObstacleGeometry", "parts"),
    ]:
        if field_after(text, anchor, name, "arena", raw=True) != "&[]":
            raise RigReadError(f"{anchor}: {name} is no longer empty; this bench has bins only")
    floor_halves = {n: const(bins, n, "bins.rs") for n in ["BIN1_FLOOR_HALF", "BIN2_FLOOR_HALF"]}
    bin_parts = {}  # const name -> (label, half-extents, offset from the bin's body)
    for m in re.finditer(r"\bconst\s+(\w+)\s*:\s*Part\s*=\s*bin_part\(", bins):
        bin_parts[m.group(1)] = [evaluate(a, floor_halves) for a in call_args(bins, m.end())]
    arena = []
    # arena_parts(): bin 1 at BIN1_POSITION for every objective, bin 2 where the objective says.
    bin2_position = field_after(layouts, pick_place, "bin2_position", "arena", raw=True)
    bins_placed = [("BIN1_POSITION", "bin1_parts"), (bin2_position, "bin2_parts")]
    for position_name, parts_field in bins_placed:
        position = const(bins, position_name, "bins.rs")
        list_name = field_after(layouts, pick_place, parts_field, "arena", raw=True)
        listed = find(bins, rf"\bconst\s+{list_name}\s*:[^=]*=\s*&\[([^\]]*)\]", "bins.rs")
        for part in re.findall(r"\w+", listed.group(1)):
            label, half, offset = bin_parts[part]
            arena.append(Part(label, [p + o for p, o in zip(position, offset)], half))

    # The box: one primitive, uniform density plus its material copies, on bin 1's floor.
    bin1 = const(bins, "BIN1_POSITION", "bins.rs")
    box_row = "const BOX: ObjectGeometry"
    (box_part,) = re.findall(r"\w+", field_after(objects, box_row, "parts", "objects.rs", raw=True))
    m = find(objects, rf"\bconst\s+{box_part}\s*:\s*Part\s*=\s*object_box\(", "objects.rs")
    _, box_half, _ = (evaluate(a) for a in call_args(objects, m.end()))
    volume = 8 * box_half[0] * box_half[1] * box_half[2]
    box_mass = const(objects, "OBJECT_DENSITY", "objects.rs") * volume + field_after(
        objects, box_row, "material_copies", "objects.rs"
    ) * const(objects, "MATERIAL_COPY_MASS", "objects.rs")
    # ObjectGeometry::spawn_z(): (START_Z_OFFSET + BIN1_POSITION.z) − bottom_offset.
    start_z = const(objects, "START_Z_OFFSET", "objects.rs", floor_halves)
    spawn_z = (start_z + bin1[2]) - field_after(objects, box_row, "bottom_offset", "objects.rs")

    def friction_of(name):
        anchor = f"const {name}: Friction"
        coefficients = ["slide", "torsion", "roll"]
        return [field_after(primitive, anchor, k, "primitive.rs") for k in coefficients]

    rig = Rig(
        dt=field_after(params, physics, "dt", "params.rs"),
        substeps=int(field_after(params, physics, "substeps", "params.rs")),
        gravity=field_after(params, physics, "gravity", "params.rs"),
        target_range=(float(target_range.group(1)), float(target_range.group(2))),
        base_position=const(fixtures, "ROBOT_BASE_POSITION", "fixtures.rs"),
        mount_link=const(robot_model, "GRIPPER_MOUNT_LINK", "robot_model.rs"),
        gripper_root=const(robot_model, "GRIPPER_ROOT_LINK", "robot_model.rs"),
        finger_joints=const(robot_model, "FINGER_JOINTS", "robot_model.rs"),
        finger_open=const(world, "FINGER_OPEN", "physics/world/"),
        finger_coupling=field_after(world, "MultibodyDofCoupling {", "coeff", "physics/world/"),
        finger_gains={
            k: field_after(params, gripper, k, "params.rs")
            for k in ["kp", "kd", "max_force", "frictionloss"]
        },
        arm_friction=float(frictions.group(1)),
        gripper_friction=float(frictions.group(2)),
        table_friction=friction_of("TABLE"),
        arena=arena,
        box=Part("box", [bin1[0], bin1[1], spawn_z], box_half),
        box_mass=box_mass,
        box_condim=int(field_after(objects, box_row, "condim", "objects.rs")),
        box_friction=friction_of("OBJECT"),
    )
    gains = "fn for_robot"
    for arm in arms:
        variant = arm.capitalize()  # iiwa -> Robot::Iiwa
        rig.arms[arm] = {
            "init_qpos": match_arm(robot, "fn init_qpos", variant, "robot.rs"),
            "kp": field_after(params, gains, "kp", "params.rs"),
            "kd": field_after(params, gains, "kd", "params.rs"),
            "armature": field_after(params, gains, "armature", "params.rs"),
            "damping": match_arm(params, "let damping", variant, "params.rs"),
            "frictionloss": match_arm(params, "let frictionloss", variant, "params.rs"),
        }
    return rig


# --- The arm from its URDFs -------------------------------------------------------------------


def numbers(values) -> str:
    return " ".join(f"{float(v):.12g}" for v in values)


def rpy_matrix(roll: float, pitch: float, yaw: float) -> np.ndarray:
    """URDF's fixed-axis roll-pitch-yaw: Rz(yaw) · Ry(pitch) · Rx(roll)."""
    cr, sr, cp, sp, cy, sy = (f(a) for a in (roll, pitch, yaw) for f in (math.cos, math.sin))
    rx = np.array([[1, 0, 0], [0, cr, -sr], [0, sr, cr]])
    ry = np.array([[cp, 0, sp], [0, 1, 0], [-sp, 0, cp]])
    rz = np.array([[cy, -sy, 0], [sy, cy, 0], [0, 0, 1]])
    return rz @ ry @ rx


@dataclass
class Pose:
    rotation: np.ndarray
    translation: np.ndarray

    @staticmethod
    def identity() -> Pose:
        return Pose(np.eye(3), np.zeros(3))

    @staticmethod
    def of(element: ET.Element) -> Pose:
        """The pose in a URDF element's `<origin xyz rpy>` (identity when absent)."""
        origin = element.find("origin")
        if origin is None:
            return Pose.identity()
        xyz, rpy = ([float(v) for v in origin.get(k, "0 0 0").split()] for k in ("xyz", "rpy"))
        return Pose(rpy_matrix(*rpy), np.array(xyz))

    def __mul__(self, other: Pose) -> Pose:
        return Pose(
            self.rotation @ other.rotation, self.rotation @ other.translation + self.translation
        )

    def mjcf(self) -> str:
        quat = np.zeros(4)
        mujoco.mju_mat2Quat(quat, self.rotation.flatten())
        return f'pos="{numbers(self.translation)}" quat="{numbers(quat)}"'


@dataclass
class Body:
    """One rigid body: a URDF link and the links fixed to it."""

    name: str
    joint: ET.Element | None  # the moving URDF joint above it (None for the base)
    origin: Pose  # its frame in the parent body's frame at q = 0
    geoms: list[str] = field(default_factory=list)
    masses: list[tuple[float, np.ndarray, np.ndarray]] = field(default_factory=list)
    children: list[Body] = field(default_factory=list)

    def add_inertial(self, inertial: ET.Element, link_in_body: Pose):
        """A link's `<inertial>`: mass, centre of mass and inertia tensor in the body frame."""
        mass = float(inertial.find("mass").get("value"))
        if mass <= 0:
            return
        i = {k: float(v) for k, v in inertial.find("inertia").attrib.items()}
        tensor = np.array([
            [i["ixx"], i["ixy"], i["ixz"]],
            [i["ixy"], i["iyy"], i["iyz"]],
            [i["ixz"], i["iyz"], i["izz"]],
        ])
        frame = link_in_body * Pose.of(inertial)
        self.masses.append((mass, frame.translation, frame.rotation @ tensor @ frame.rotation.T))

    def inertial_mjcf(self) -> str:
        """Our `MassAccumulator`: the links' inertials summed about the common centre of mass
        (parallel-axis theorem)."""
        mass = sum(m for m, _, _ in self.masses)
        if mass <= 0:
            return ""
        com = sum(m * c for m, c, _ in self.masses) / mass
        inertia = sum(
            tensor + m * (np.dot(c - com, c - com) * np.eye(3) - np.outer(c - com, c - com))
            for m, c, tensor in self.masses
        )
        full = [inertia[0, 0], inertia[1, 1], inertia[2, 2], inertia[0, 1], inertia[0, 2],
                inertia[1, 2]]
        return f'<inertial pos="{numbers(com)}" mass="{mass:.12g}" fullinertia="{numbers(full)}"/>'


def collision_geoms(link: ET.Element, link_in_body: Pose, friction: float) -> list[str]:
    """MJCF geoms of a link's collisions. A cylinder `N` with spheres `N_end1`, `N_end2` is one
    capsule: the cylinder's pose and radius, half-length = half the cylinder's length."""
    collisions = {c.get("name"): c for c in link.findall("collision")}
    capsules = {n for n in collisions if f"{n}_end1" in collisions and f"{n}_end2" in collisions}
    end_spheres = {f"{n}{end}" for n in capsules for end in ("_end1", "_end2")}
    geoms = []
    for name, collision in collisions.items():
        if name in end_spheres:
            continue
        shape = collision.find("geometry")[0]
        if shape.tag == "box":
            kind, size = "box", [float(v) / 2 for v in shape.get("size").split()]
        elif shape.tag == "sphere":
            kind, size = "sphere", [float(shape.get("radius"))]
        elif shape.tag == "cylinder":
            radius, length = float(shape.get("radius")), float(shape.get("length"))
            kind, size = ("capsule" if name in capsules else "cylinder"), [radius, length / 2]
            for end in (f"{name}_end1", f"{name}_end2") if name in capsules else ():
                sphere = collisions[end].find("geometry")[0]
                if sphere.tag != "sphere" or abs(float(sphere.get("radius")) - radius) > 1e-12:
                    raise RigReadError(f"{end} is not a sphere of the radius of {name}")
        else:
            raise RigReadError(f"link {link.get('name')}: no MuJoCo geom for <{shape.tag}>")
        pose = link_in_body * Pose.of(collision)
        geoms.append(
            f'<geom name="{name}" type="{kind}" size="{numbers(size)}" {pose.mjcf()} '
            f'friction="{friction:.12g}" {ROBOT_BITS}/>'
        )
    return geoms


def arm_bodies(arm: str, rig: Rig) -> Body:
    """The arm with the gripper mounted, as a tree of bodies (robot_model.rs's merge: a link
    reached through a fixed joint joins its parent's body, a moving joint starts a new one)."""
    arm_urdf = ET.parse(REPO / "urdf" / f"{arm}.urdf").getroot()
    gripper_urdf = ET.parse(REPO / "urdf" / "rethink_gripper.urdf").getroot()
    links = {link.get("name"): link for u in (arm_urdf, gripper_urdf) for link in u.findall("link")}
    # Ours tags colliders by name; every collision of the gripper's URDF is a gripper one.
    gripper_links = {link.get("name") for link in gripper_urdf.findall("link")}
    mount = ET.fromstring(
        f'<joint name="gripper_mount" type="fixed"><parent link="{rig.mount_link}"/>'
        f'<child link="{rig.gripper_root}"/></joint>'
    )
    children: dict[str, list[ET.Element]] = {}
    for joint in arm_urdf.findall("joint") + gripper_urdf.findall("joint") + [mount]:
        children.setdefault(joint.find("parent").get("link"), []).append(joint)
    child_links = {j.find("child").get("link") for js in children.values() for j in js}
    (root,) = [name for name in links if name not in child_links]

    def visit(name: str, body: Body, link_in_body: Pose):
        link = links[name]
        if link.find("inertial") is not None:
            body.add_inertial(link.find("inertial"), link_in_body)
        friction = rig.gripper_friction if name in gripper_links else rig.arm_friction
        body.geoms += collision_geoms(link, link_in_body, friction)
        for joint in children.get(name, []):
            child = joint.find("child").get("link")
            origin = link_in_body * Pose.of(joint)
            if joint.get("type") == "fixed":
                visit(child, body, origin)
            else:
                body.children.append(Body(child, joint, origin))
                visit(child, body.children[-1], Pose.identity())

    # The base sits at ROBOT_BASE_POSITION with the world's orientation (robot_base_pose()).
    base = Body(root, None, Pose(np.eye(3), np.array(rig.base_position)))
    visit(root, base, Pose.identity())
    return base


# --- The MJCF ---------------------------------------------------------------------------------


def body_mjcf(body: Body, arm: dict, rig: Rig, joint_names: list[str]) -> str:
    """A body and those below it; appends their joints' names to `joint_names` in tree order."""
    lines = [f'<body name="{body.name}" {body.origin.mjcf()} gravcomp="1">', body.inertial_mjcf()]
    if body.joint is not None:
        name, kind = body.joint.get("name"), body.joint.get("type")
        limit = body.joint.find("limit")
        axis = body.joint.find("axis")
        attrs = f'name="{name}" axis="{"1 0 0" if axis is None else axis.get("xyz")}"'
        if kind == "continuous":
            attrs += ' limited="false"'
        else:
            attrs += f' range="{limit.get("lower")} {limit.get("upper")}"'
        if name in rig.finger_joints:
            # Fingers: no armature or damping (their servos set how they move), dry friction.
            g = rig.finger_gains
            force = g["max_force"]
            attrs += (
                f' type="slide" frictionloss="{g["frictionloss"]:.12g}"'
                f' actuatorfrcrange="{-force:.12g} {force:.12g}"'
            )
        else:
            j = len(joint_names)
            effort = float(limit.get("effort"))
            attrs += (
                f' type="hinge" armature="{arm["armature"][j]:.12g}"'
                f' damping="{arm["damping"][j]:.12g}" frictionloss="{arm["frictionloss"]:.12g}"'
                f' actuatorfrcrange="{-effort:.12g} {effort:.12g}"'
                # Gravity compensation is actuator force, clamped with it to the effort limit.
                ' actuatorgravcomp="true"'
            )
        joint_names.append(name)
        lines.append(f"<joint {attrs}/>")
    lines += body.geoms
    lines += [body_mjcf(child, arm, rig, joint_names) for child in body.children]
    lines.append("</body>")
    return "\n".join(lines)


def scene_mjcf(arm: str, rig: Rig) -> tuple[str, list[str]]:
    """The scene's MJCF, and its joint names: the 7 arm joints, then the two fingers."""
    joint_names: list[str] = []
    robot = body_mjcf(arm_bodies(arm, rig), rig.arms[arm], rig, joint_names)
    if len(joint_names) != 9 or joint_names[7:] != rig.finger_joints:
        raise RigReadError(f"{arm}: expected 7 arm joints, then the fingers: {joint_names}")
    arena = "\n".join(
        f'<geom name="{p.name}" type="box" pos="{numbers(p.centre)}" size="{numbers(p.half)}" '
        f'friction="{numbers(rig.table_friction)}" {SCENE_BITS}/>'
        for p in rig.arena
    )
    # The box's inertia: a uniform solid of its mass, as ours (density = mass / volume).
    m = rig.box_mass
    x, y, z = (2 * h for h in rig.box.half)
    box_inertia = [m / 12 * (y**2 + z**2), m / 12 * (x**2 + z**2), m / 12 * (x**2 + y**2)]
    f = rig.finger_gains
    kps = [*rig.arms[arm]["kp"], f["kp"], f["kp"]]
    kds = [*rig.arms[arm]["kd"], f["kd"], f["kd"]]
    actuators = "\n".join(
        f'<position name="{name}" joint="{name}" kp="{kp:.12g}" kv="{kd:.12g}"/>'
        for name, kp, kd in zip(joint_names, kps, kds)
    )
    left, right = rig.finger_joints
    xml = f"""
<mujoco model="composuite-{arm}-pick-place">
  <compiler angle="radian" inertiafromgeom="false" autolimits="true"/>
  <option timestep="{rig.dt:.12g}" gravity="0 0 {-rig.gravity:.12g}" solver="Newton"
          integrator="implicitfast"/>
  <worldbody>
    <!-- The ground: infinite, like our half-space. -->
    <geom name="ground" type="plane" size="0 0 1" {SCENE_BITS}/>
{arena}
{robot}
    <body name="box" pos="{numbers(rig.box.centre)}">
      <freejoint name="box"/>
      <inertial pos="0 0 0" mass="{m:.12g}" diaginertia="{numbers(box_inertia)}"/>
      <geom name="box" type="box" size="{numbers(rig.box.half)}" condim="{rig.box_condim}"
            friction="{numbers(rig.box_friction)}" {BOX_BITS}/>
    </body>
  </worldbody>
  <equality>
    <!-- The fingers move as one, as our loader couples them: q_right = coeff × q_left. -->
    <joint joint1="{right}" joint2="{left}" polycoef="0 {rig.finger_coupling:.12g} 0 0 0"/>
  </equality>
  <actuator>
{actuators}
  </actuator>
</mujoco>
"""
    return xml, joint_names


# --- Running ----------------------------------------------------------------------------------


@dataclass
class Scene:
    model: mujoco.MjModel
    data: mujoco.MjData
    arm_qpos: np.ndarray  # qpos indices of the 7 arm joints
    home: np.ndarray  # qpos at reset: start pose, fingers open, the box at its spawn pose
    home_ctrl: np.ndarray  # ctrl at reset: 7 arm set points, then the fingers'
    box_z: int  # qpos index of the box's z
    limits: list[tuple[float, float] | None]  # arm joint ranges, None if continuous
    velocity: np.ndarray  # arm joint velocity limits (rad/s), from the URDF


def build_scene(arm: str, rig: Rig) -> Scene:
    xml, joint_names = scene_mjcf(arm, rig)
    model = mujoco.MjModel.from_xml_string(xml)
    joints = [model.joint(n) for n in joint_names]
    qadr = np.array([j.qposadr[0] for j in joints])
    fingers = [rig.finger_open, rig.finger_coupling * rig.finger_open]
    home_ctrl = np.array([*rig.arms[arm]["init_qpos"], *fingers])
    home = model.qpos0.copy()
    home[qadr] = home_ctrl
    box = model.joint("box").qposadr[0]
    home[box:box + 7] = [*rig.box.centre, 1, 0, 0, 0]
    urdf_limits = {
        j.get("name"): j.find("limit")
        for j in ET.parse(REPO / "urdf" / f"{arm}.urdf").getroot().findall("joint")
    }
    return Scene(
        model=model,
        data=mujoco.MjData(model),
        arm_qpos=qadr[:7],
        home=home,
        home_ctrl=home_ctrl,
        box_z=box + 2,
        limits=[tuple(j.range) if model.jnt_limited[j.id] else None for j in joints[:7]],
        velocity=np.array([float(urdf_limits[n].get("velocity")) for n in joint_names[:7]]),
    )


def control_sequence(scene: Scene, rig: Rig, steps: int, seed: int):
    """Per control step: the random target (the start pose ± the bench's range, clamped into the
    joint limits as `validate_arm_targets` does) and the set point sent, which moves toward it by
    at most the joint's velocity limit × one control period (ours: × dt, every physics step)."""
    rng = np.random.default_rng(seed)
    start = scene.home_ctrl[:7]
    targets = start + rng.uniform(*rig.target_range, size=(steps, 7))
    for j, limit in enumerate(scene.limits):
        if limit is not None:
            targets[:, j] = np.clip(targets[:, j], *limit)
    max_move = scene.velocity * rig.dt * rig.substeps
    setpoints = np.empty_like(targets)
    setpoint = start.copy()
    for k in range(steps):
        setpoint = setpoint + np.clip(targets[k] - setpoint, -max_move, max_move)
        setpoints[k] = setpoint
    return targets, setpoints


def box_at_rest(scene: Scene, rig: Rig) -> tuple[bool, float]:
    """Whether the box is within 1 cm of its spawn height (resting in bin 1), and its z."""
    z = float(scene.data.qpos[scene.box_z])
    return abs(z - rig.box.centre[2]) < 0.01, z


def run_once(scene: Scene, rig: Rig, targets: np.ndarray, setpoints: np.ndarray) -> dict:
    model, data = scene.model, scene.data
    mujoco.mj_resetData(model, data)
    data.qpos[:] = scene.home
    data.ctrl[:] = scene.home_ctrl
    mujoco.mj_forward(model, data)
    mujoco.mj_step(model, data, nstep=SETTLE_STEPS)  # untimed
    settled, settled_z = box_at_rest(scene, rig)

    steps = len(targets)
    q_after = np.empty((steps, 7))
    contacts = rows = 0
    # The bookkeeping in the loop costs ~2 µs per control step (< 0.1 µs per physics step).
    start = time.perf_counter_ns()
    for k in range(steps):
        data.ctrl[:7] = setpoints[k]
        mujoco.mj_step(model, data, nstep=rig.substeps)
        contacts += data.ncon
        rows += data.nefc
        q_after[k] = data.qpos[scene.arm_qpos]
    elapsed_ns = time.perf_counter_ns() - start

    still, final_z = box_at_rest(scene, rig)
    return {
        "us_per_step": elapsed_ns / 1e3 / (steps * rig.substeps),
        "mean_contacts": contacts / steps,
        "mean_constraint_rows": rows / steps,
        "tracking_rad": float(np.abs(q_after - targets).mean()),
        "tracking_setpoint_rad": float(np.abs(q_after - setpoints).mean()),
        "box_settled": settled,
        "box_z_settled": settled_z,
        "box_at_rest_after": still,
        "box_z_after": final_z,
    }


def pin(core: int) -> str:
    if not hasattr(os, "sched_setaffinity"):
        return "not pinned (no sched_setaffinity here)"
    try:
        os.sched_setaffinity(0, {core})
        return f"pinned to core {core}"
    except OSError as e:
        return f"not pinned to core {core} ({e.strerror})"


def main():
    global mujoco
    import mujoco as loaded

    mujoco = loaded
    parser = argparse.ArgumentParser(
        description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter
    )
    parser.add_argument("--arms", nargs="+", choices=ARMS, default=ARMS)
    parser.add_argument(
        "--steps", type=int, default=2000, help="control steps timed per run (25 physics steps)"
    )
    parser.add_argument("--repeats", type=int, default=5, help="runs per arm (best and median)")
    parser.add_argument("--core", type=int, default=1, help="CPU core to pin to, where allowed")
    parser.add_argument("--seed", type=int, default=1, help="seed of the random targets")
    parser.add_argument("--json", action="store_true", help="one JSON list instead of the table")
    args = parser.parse_args()
    if args.steps < 1 or args.repeats < 1:
        parser.error("--steps and --repeats must be at least 1")
    pinned = pin(args.core)
    try:
        rig = read_rig(args.arms)
    except (RigReadError, OSError) as e:
        sys.exit(f"bench_mujoco: could not read our rig from the sources: {e}")

    results = []
    for arm in args.arms:
        scene = build_scene(arm, rig)
        targets, setpoints = control_sequence(scene, rig, args.steps, args.seed)
        runs = [run_once(scene, rig, targets, setpoints) for _ in range(args.repeats)]
        times = [r["us_per_step"] for r in runs]
        model = scene.model
        results.append({
            "arm": arm,
            "us_per_step_best": min(times),
            "us_per_step_median": statistics.median(times),
            "control_steps_per_s": 1e6 / (min(times) * rig.substeps),
            "nv": model.nv,
            "nbody": model.nbody,
            "collision_geoms": int(np.count_nonzero(model.geom_contype | model.geom_conaffinity)),
            # Every run is the same trajectory; the last one's figures stand for all.
            **{k: v for k, v in runs[-1].items() if k != "us_per_step"},
            "runs_us_per_step": times,
        })

    if args.json:
        print(json.dumps(results, indent=2))
        return
    print(
        f"MuJoCo {mujoco.__version__}: timestep {rig.dt} s, {rig.substeps} steps per control "
        f"step, Newton (≤ {model.opt.iterations} iterations), pyramidal cone, implicitfast; "
        f"{args.steps} control steps, best and median of {args.repeats} runs; {pinned}"
    )
    header = (
        f"{'arm':<6} {'us/step':>8} {'median':>8} {'control steps/s':>16} {'nv':>3} "
        f"{'geoms':>6} {'contacts':>9} {'rows':>6} {'|q-target| rad':>15} {'|q-set pt|':>11}  box"
    )
    print(header)
    print("-" * len(header))
    for r in results:
        box = "at rest" if r["box_settled"] else f"NOT at rest (z {r['box_z_settled']:.4f})"
        box += ", still after" if r["box_at_rest_after"] else f", moved (z {r['box_z_after']:.4f})"
        print(
            f"{r['arm']:<6} {r['us_per_step_best']:8.1f} {r['us_per_step_median']:8.1f} "
            f"{r['control_steps_per_s']:16.0f} {r['nv']:3d} {r['collision_geoms']:6d} "
            f"{r['mean_contacts']:9.1f} {r['mean_constraint_rows']:6.1f} "
            f"{r['tracking_rad']:15.3f} {r['tracking_setpoint_rad']:11.3f}  {box}"
        )
    print(
        "\ncontacts, rows: mean data.ncon and data.nefc after each control step. |q-target|: mean"
        " over joints and control steps\nafter each control step, from the random target;"
        " |q-set pt|: from the rate-limited set point sent. box: within 1 cm of its\nspawn height"
        " in bin 1 after settling, and after the run. Nothing is asserted."
    )


if __name__ == "__main__":
    main()
