"""Our message layer against real ROS 2 Jazzy: composuite_msgs as colcon builds it for rclpy
(rosidl generators, Fast DDS type support), rclpy's own serializer, and the type hashes Jazzy's
rosidl_generator_type_description writes. Needs the venv of scripts/python-env with
`install/setup.sh` of scripts/build-msgs-colcon sourced (the test command does both)."""

from __future__ import annotations

import importlib
import json
import random
from pathlib import Path

import pytest

import msgcheck

SEED = 7
PER_TYPE = 20
# Standard packages the PyPI Jazzy wheels provide (there are no control_msgs/tf2_msgs wheels;
# those two types are covered by the rosbags tests), composuite_msgs, and simulation_interfaces
# (colcon-built from msgs/simulation_interfaces, whose hashes msgs/tests/simulation_interfaces.rs
# pins to those of upstream's 1.5.1 files).
JAZZY_PACKAGES = {
    "builtin_interfaces", "std_msgs", "geometry_msgs", "sensor_msgs", "rosgraph_msgs", "service_msgs",
    "visualization_msgs", "composuite_msgs", "simulation_interfaces",
}


@pytest.fixture(scope="module")
def described():
    return json.loads(msgcheck.probe("describe"))


@pytest.fixture(scope="module")
def store():
    return msgcheck.rosbags_store()


def rclpy_class(name: str):
    """The rclpy class of `pkg/msg/Name` or `pkg/srv/Name_{Request,Response,Event}`."""
    package, kind, type_name = name.split("/")
    module = importlib.import_module(f"{package}.{kind}")
    if kind == "msg":
        return getattr(module, type_name)
    service, half = type_name.rsplit("_", 1)
    return getattr(getattr(module, service), half)


def to_rclpy(store, name: str, plain: dict):
    from rosbags.interfaces import Nodetype

    msg = rclpy_class(name)()
    for field, (kind, rest) in store.fielddefs[name][1]:
        if field == msgcheck.EMPTY_FIELD:
            continue  # rclpy's class of an empty type has no attribute; it sends 0
        value = plain[field]
        if kind == Nodetype.NAME:
            value = to_rclpy(store, rest, value)
        elif kind in (Nodetype.ARRAY, Nodetype.SEQUENCE) and rest[0][0] == Nodetype.NAME:
            value = [to_rclpy(store, rest[0][1], v) for v in value]
        setattr(msg, field, value)
    return msg


def jazzy_types(described) -> list[str]:
    return [n for n in described["messages"] if n.split("/")[0] in JAZZY_PACKAGES]


def test_rclpy_imports_every_composuite_type():
    msg = importlib.import_module("composuite_msgs.msg")
    srv = importlib.import_module("composuite_msgs.srv")
    for path in sorted((msgcheck.MSGS / "msg").glob("*.msg")):
        assert hasattr(msg, path.stem), path.stem
    for path in sorted((msgcheck.MSGS / "srv").glob("*.srv")):
        service = getattr(srv, path.stem)
        assert service.Request and service.Response and service.Event
    assert msg.Observation.FLAT_SIZE_WITH_TASK == 93


def test_rclpy_serialized_messages_decode_equal_in_rust_and_back(store, described):
    from rclpy.serialization import deserialize_message, serialize_message

    rng = random.Random(SEED)
    sent = []
    for name in jazzy_types(described):
        for _ in range(PER_TYPE):
            plain = msgcheck.random_plain(store, rng, name)
            sent.append((name, plain, serialize_message(to_rclpy(store, name, plain))))
    assert len({n for n, _, _ in sent}) >= 30
    requests = "\n".join(json.dumps({"type": n, "cdr": b.hex()}) for n, _, b in sent)
    answers = msgcheck.probe_lines("roundtrip", stdin=requests)
    assert len(answers) == len(sent)
    for (name, plain, _), answer in zip(sent, answers):
        assert answer["ok"], f"{name}: {answer.get('error')}"
        expected = msgcheck.canonical(store, name, plain)
        # Values, not bytes: rclpy leaves whatever memory held in alignment padding.
        assert msgcheck.canonical(store, name, answer["value"]) == expected, name
        back = deserialize_message(bytes.fromhex(answer["cdr"]), rclpy_class(name))
        assert msgcheck.canonical(store, name, back) == expected, name


def test_type_hashes_equal_jazzy_generator_output(described):
    """rosidl_generator_type_description installs share/<pkg>/<kind>/<Type>.json with the hashes
    of the type and everything it references; ours must equal all of them."""
    from ament_index_python.packages import get_package_share_directory

    expected: dict[str, str] = {}
    for package in JAZZY_PACKAGES:
        share = Path(get_package_share_directory(package))
        for path in share.glob("*/*.json"):
            if path.parent.name in ("msg", "srv", "action"):
                for entry in json.loads(path.read_text())["type_hashes"]:
                    expected[entry["type_name"]] = entry["hash_string"]
    ours = {n: v["type_hash"] for n, v in described["messages"].items()}
    ours.update({n: v["type_hash"] for n, v in described["services"].items()})
    compared = [n for n in ours if n in expected]
    assert [n for n in compared if ours[n] != expected[n]] == []
    # every composuite type (13 msgs, 3 services with request/response/event) and the standard ones
    assert sum(n.startswith("composuite_msgs/") for n in compared) == 13 + 3 * 4
    # every simulation_interfaces type we generate: 15 msgs, 22 services with request/response/
    # event, the SimulateSteps goal/result/feedback
    assert sum(n.startswith("simulation_interfaces/") for n in compared) == 15 + 22 * 4 + 3
    assert len(compared) >= 25 + 13
    # the scene markers' types, against the ros-jazzy-visualization-msgs wheel
    assert {"visualization_msgs/msg/MarkerArray", "visualization_msgs/msg/Marker", "visualization_msgs/msg/MeshFile",
            "visualization_msgs/msg/UVCoordinate", "sensor_msgs/msg/CompressedImage",
            "std_msgs/msg/ColorRGBA"} <= set(compared)
