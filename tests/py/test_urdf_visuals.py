"""The URDFs as an independent parser (yourdfpy, PyPI) reads them: each file and each arm's
robot_description loads; every link with a body has visuals of standard types (box, cylinder,
sphere) with a colour; no geometry is of a type outside standard URDF; and the forward
kinematics of the parsed model — the frames the visuals hang on — agree with the simulator's
link poses after the arm has moved (the `link_poses` example of composuite_core).

Run: cargo build -p composuite_core --example link_poses; pytest tests/py/test_urdf_visuals.py
"""
import json
import subprocess

import numpy as np
import pytest
import yourdfpy

import node_suite

URDF_DIR = node_suite.REPO / "urdf"
FILES = sorted(URDF_DIR.glob("*.urdf"))
# Frames without a body: the gripper mount and the reference's end-effector point.
FRAME_LINKS = {"right_hand", "grip_site"}
STANDARD = ("box", "cylinder", "sphere")
# The simulator's poses are rapier's (f32): a few µm of rounding over the chain.
POSITION_TOLERANCE = 1e-4  # m
ROTATION_TOLERANCE = 1e-4  # rad


def load(path):
    return yourdfpy.URDF.load(str(path), build_scene_graph=True, load_meshes=False,
                              build_collision_scene_graph=False)


def geometry_type(geometry):
    kinds = [k for k in ("box", "cylinder", "sphere", "mesh") if getattr(geometry, k) is not None]
    assert len(kinds) == 1, geometry
    return kinds[0]


def colour(robot, visual):
    material = visual.material
    assert material is not None, visual.name
    if material.color is not None:
        return material.color.rgba
    named = {m.name: m for m in robot.materials}
    assert material.name in named and named[material.name].color is not None, material.name
    return named[material.name].color.rgba


def check_visuals(urdf):
    robot = urdf.robot
    without = set()
    for link in robot.links:
        if not link.visuals:
            without.add(link.name)
            assert not link.collisions, f"{link.name} collides but has no visual"
            continue
        for visual in link.visuals:
            assert geometry_type(visual.geometry) in STANDARD, (link.name, visual.name)
            rgba = np.asarray(colour(robot, visual))
            assert rgba.shape == (4,) and np.all((0 <= rgba) & (rgba <= 1)), (visual.name, rgba)
        for collision in link.collisions:
            assert geometry_type(collision.geometry) in STANDARD, (link.name, collision.name)
    assert without <= FRAME_LINKS, without


@pytest.mark.parametrize("path", FILES, ids=[p.name for p in FILES])
def test_each_urdf_loads_with_standard_visuals_and_collisions(path):
    assert len(FILES) == 5  # four arms and the gripper
    check_visuals(load(path))


@pytest.fixture(scope="module")
def simulated():
    binary = node_suite.node_dir() / "examples" / "link_poses"
    if not binary.is_file():
        raise FileNotFoundError(f"{binary} not found: cargo build -p composuite_core --example link_poses")
    out = subprocess.run([str(binary)], check=True, capture_output=True, text=True, timeout=120).stdout
    return [json.loads(line) for line in out.splitlines()]


def pose_matrix(pose):
    x, y, z, qw, qx, qy, qz = pose
    rotation = np.array([
        [1 - 2 * (qy * qy + qz * qz), 2 * (qx * qy - qz * qw), 2 * (qx * qz + qy * qw)],
        [2 * (qx * qy + qz * qw), 1 - 2 * (qx * qx + qz * qz), 2 * (qy * qz - qx * qw)],
        [2 * (qx * qz - qy * qw), 2 * (qy * qz + qx * qw), 1 - 2 * (qx * qx + qy * qy)],
    ])
    matrix = np.eye(4)
    matrix[:3, :3] = rotation
    matrix[:3, 3] = (x, y, z)
    return matrix


def test_robot_descriptions_have_visuals_and_their_kinematics_follow_the_simulator(simulated, tmp_path):
    assert [s["robot"] for s in simulated] == ["IIWA", "Jaco", "Gen3", "Panda"]
    for sample in simulated:
        path = tmp_path / f"{sample['robot']}.urdf"
        path.write_text(sample["urdf"])
        urdf = load(path)
        check_visuals(urdf)
        assert set(urdf.actuated_joint_names) == set(sample["joints"]), sample["robot"]
        zero = load(path)  # every joint at 0
        urdf.update_cfg(sample["joints"])
        base = urdf.base_link
        world_from_base = pose_matrix(sample["links"][base])
        assert set(sample["links"]) == set(urdf.link_map), sample["robot"]
        moved = 0
        for link, pose in sample["links"].items():
            ours = world_from_base @ urdf.get_transform(link, base)
            theirs = pose_matrix(pose)
            offset = np.linalg.norm(ours[:3, 3] - theirs[:3, 3])
            cos = (np.trace(ours[:3, :3].T @ theirs[:3, :3]) - 1) / 2
            angle = np.arccos(np.clip(cos, -1.0, 1.0))
            assert offset < POSITION_TOLERANCE and angle < ROTATION_TOLERANCE, (
                sample["robot"], link, offset, angle)
            # Count links away from their zero-pose place: the joints were really exercised.
            at_zero = zero.get_transform(link, base)[:3, 3]
            if np.linalg.norm(at_zero - urdf.get_transform(link, base)[:3, 3]) > 0.01:
                moved += 1
        assert moved >= 5, (sample["robot"], moved)
