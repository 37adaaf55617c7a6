"""Helpers shared by the message interop tests: run the Rust `msg_probe`, build a rosbags type
store from our own .msg/.srv files, and compare decoded values exactly (float bits, not ==)."""

from __future__ import annotations

import json
import os
import random
import struct
import subprocess
from pathlib import Path

REPO = Path(__file__).resolve().parents[2]
MSGS = REPO / "msgs"


def probe_path() -> Path:
    """The `msg_probe` example binary built by `cargo test` (path given by the test command)."""
    path = os.environ.get("COMPOSUITE_MSG_PROBE")
    if not path:
        target = Path(os.environ.get("CARGO_TARGET_DIR", REPO / "target"))
        path = str(target / "debug" / "examples" / "msg_probe")
    if not Path(path).is_file():
        raise FileNotFoundError(
            f"{path} not found: build it with `cargo build -p composuite_msgs --example msg_probe` "
            "or set COMPOSUITE_MSG_PROBE"
        )
    return Path(path)


def probe(*args: str, stdin: str | None = None) -> str:
    result = subprocess.run(
        [str(probe_path()), *args], input=stdin, capture_output=True, text=True, check=False
    )
    if result.returncode != 0:
        raise RuntimeError(f"msg_probe {' '.join(args)} failed: {result.stderr}")
    return result.stdout


def probe_lines(*args: str, stdin: str | None = None) -> list[dict]:
    return [json.loads(line) for line in probe(*args, stdin=stdin).splitlines() if line.strip()]


def interface_files(package: str, folder: Path) -> tuple[dict[str, str], dict[str, str], dict[str, str]]:
    """The .msg, .srv and .action texts of one package folder, by type name."""
    def texts(kind: str) -> dict[str, str]:
        return {f"{package}/{kind}/{p.stem}": p.read_text() for p in sorted((folder / kind).glob(f"*.{kind}"))}
    return texts("msg"), texts("srv"), texts("action")


# The packages that are not composuite_msgs: standard ROS 2 messages (msgs/standard), the
# ros2_control subsets (msgs/ros2_control) and the standard simulation interfaces
# (msgs/simulation_interfaces), one folder per package in each.
OTHER_PACKAGE_FOLDERS = ("standard", "ros2_control", "simulation_interfaces")
# Those of them that are colcon packages of their own (msgs/standard is not: the Jazzy wheels
# provide those packages).
COLCON_PACKAGE_FOLDERS = ("ros2_control", "simulation_interfaces")


def other_message_files() -> dict[str, Path]:
    """The .msg files of every package under OTHER_PACKAGE_FOLDERS, by type name."""
    return {f"{p.parent.parent.name}/msg/{p.stem}": p
            for folder in OTHER_PACKAGE_FOLDERS
            for p in sorted((MSGS / folder).glob("*/msg/*.msg"))}


def own_interface_files() -> tuple[dict[str, str], dict[str, str]]:
    """composuite_msgs .msg and .srv texts by type name."""
    msgs, srvs, _ = interface_files("composuite_msgs", MSGS)
    return msgs, srvs


def rosbags_store():
    """The Jazzy type store of `rosbags`, plus our package, the ros2_control subsets
    (msgs/ros2_control/: control_msgs and controller_manager_msgs are not in rosbags' Jazzy
    store) and simulation_interfaces (msgs/simulation_interfaces/) registered from our own files."""
    from rosbags.interfaces import Nodetype
    from rosbags.typesys import Stores, get_types_from_msg, get_typestore

    store = get_typestore(Stores.ROS2_JAZZY)
    types: dict = {}

    def parts(name: str, text: str, suffixes: tuple[str, ...]) -> None:
        # rosbags resolves relative names against a msg-style name; parse as msg, then rename.
        kind = name.split("/")[1]
        for suffix, part_text in zip(suffixes, text.split("\n---\n"), strict=True):
            parsed = get_types_from_msg(part_text, f"{name.replace(f'/{kind}/', '/msg/')}_{suffix}")
            (_, definition), = parsed.items()
            types[f"{name}_{suffix}"] = definition

    folders = [("composuite_msgs", MSGS)] + [(p.name, p) for folder in COLCON_PACKAGE_FOLDERS
                                             for p in sorted((MSGS / folder).iterdir())
                                             if (p / "package.xml").is_file()]
    for package, folder in folders:
        msgs, srvs, actions = interface_files(package, folder)
        for name, text in msgs.items():
            types.update(get_types_from_msg(text, name))
        for name, text in srvs.items():
            parts(name, text, ("Request", "Response"))
            # The event message of a service, as ROS 2 defines it.
            types[f"{name}_Event"] = (
                [],
                [
                    ("info", (Nodetype.NAME, "service_msgs/msg/ServiceEventInfo")),
                    ("request", (Nodetype.SEQUENCE, ((Nodetype.NAME, f"{name}_Request"), 1))),
                    ("response", (Nodetype.SEQUENCE, ((Nodetype.NAME, f"{name}_Response"), 1))),
                ],
            )
        for name, text in actions.items():
            parts(name, text, ("Goal", "Result", "Feedback"))
    store.register(types)
    return store


# ---- exact value comparison, driven by the rosbags field definitions ----------------------------


def canonical(store, typename: str, value) -> object:
    """A comparable form of a message value (a rosbags object or our JSON dict): floats become
    their hex bit pattern (so -0.0 != 0.0), float32 values are rounded to float32 first."""
    _, fields = store.fielddefs[typename]
    # rclpy's class of an empty type has no attribute for EMPTY_FIELD.
    get = ((lambda n: value[n]) if isinstance(value, dict)
           else (lambda n: getattr(value, n, 0) if n == EMPTY_FIELD else getattr(value, n)))
    return {name: canonical_field(store, desc, get(name)) for name, desc in fields}


def canonical_field(store, desc, value):
    from rosbags.interfaces import Nodetype

    kind, rest = desc
    if kind == Nodetype.BASE:
        return canonical_base(rest[0], value)
    if kind == Nodetype.NAME:
        return canonical(store, rest, value)
    (sub_kind, sub_rest), _count = rest
    items = list(value)
    if sub_kind == Nodetype.BASE:
        return [canonical_base(sub_rest[0], v) for v in items]
    return [canonical(store, sub_rest, v) for v in items]


def canonical_base(base: str, value):
    if base == "float32":
        return struct.unpack("<f", struct.pack("<f", float(value)))[0].hex()
    if base == "float64":
        return float(value).hex()
    if base == "bool":
        return bool(value)
    if base == "string":
        return str(value)
    if base in ("char", "byte"):
        # Octets in ROS 2; mcap_ros2 reads char and rosbags reads byte as a signed int8, so
        # compare the byte.
        return int(value) & 0xFF
    return int(value)


# The one field ROS 2 gives a type that has none (e.g. an empty service request).
EMPTY_FIELD = "structure_needs_at_least_one_member"


# ---- random values on the Python side (independent of the Rust generator) ---------------------

STRING_CHARS = "abcXYZ019 _-\"\\/#\t\néüß漢字🤖"
INT_RANGES = {
    "int8": (-(2**7), 2**7 - 1), "uint8": (0, 2**8 - 1), "byte": (0, 255), "char": (0, 255),
    "int16": (-(2**15), 2**15 - 1), "uint16": (0, 2**16 - 1),
    "int32": (-(2**31), 2**31 - 1), "uint32": (0, 2**32 - 1),
    "int64": (-(2**63), 2**63 - 1), "uint64": (0, 2**64 - 1),
}


def random_float(rng: random.Random, bits: int) -> float:
    choice = rng.randrange(6)
    if choice == 0:
        return 0.0
    if choice == 1:
        return -0.0
    if choice == 2:
        return rng.uniform(-10, 10)
    while True:
        if bits == 32:
            v = struct.unpack("<f", struct.pack("<I", rng.getrandbits(32)))[0]
        else:
            v = struct.unpack("<d", struct.pack("<Q", rng.getrandbits(64)))[0]
        if v == v and abs(v) != float("inf"):
            return v


def random_base(rng: random.Random, base: str, bound: int):
    if base == "bool":
        return rng.random() < 0.5
    if base in ("float32", "float64"):
        return random_float(rng, 32 if base == "float32" else 64)
    if base == "string":
        text = ""
        for _ in range(rng.randrange(0, 10)):
            c = rng.choice(STRING_CHARS)
            if bound and len((text + c).encode()) > bound:
                break
            text += c
        return text
    lo, hi = INT_RANGES[base]
    return rng.randint(lo, hi)


def random_plain(store, rng: random.Random, typename: str, max_len: int = 3) -> dict:
    """A random value as a plain dict tree."""
    from rosbags.interfaces import Nodetype

    _, fields = store.fielddefs[typename]
    out = {}
    for name, (kind, rest) in fields:
        if name == EMPTY_FIELD:
            out[name] = 0  # what every ROS 2 peer (rclpy included) sends there
        elif kind == Nodetype.BASE:
            out[name] = random_base(rng, rest[0], rest[1])
        elif kind == Nodetype.NAME:
            out[name] = random_plain(store, rng, rest, max_len)
        else:
            (sub_kind, sub_rest), count = rest
            n = count if kind == Nodetype.ARRAY else rng.randint(0, count or max_len)
            if sub_kind == Nodetype.BASE:
                out[name] = [random_base(rng, sub_rest[0], sub_rest[1]) for _ in range(n)]
            else:
                out[name] = [random_plain(store, rng, sub_rest, max_len) for _ in range(n)]
    return out


def to_rosbags(store, typename: str, plain: dict):
    """Build a rosbags message object from a plain dict tree."""
    import numpy as np
    from rosbags.interfaces import Nodetype

    numpy_types = {
        "bool": np.bool_, "int8": np.int8, "uint8": np.uint8, "byte": np.uint8, "char": np.uint8,
        "int16": np.int16, "uint16": np.uint16, "int32": np.int32, "uint32": np.uint32,
        "int64": np.int64, "uint64": np.uint64, "float32": np.float32, "float64": np.float64,
    }
    _, fields = store.fielddefs[typename]
    kwargs = {}
    for name, (kind, rest) in fields:
        value = plain[name]
        if kind == Nodetype.BASE:
            kwargs[name] = value
        elif kind == Nodetype.NAME:
            kwargs[name] = to_rosbags(store, rest, value)
        else:
            (sub_kind, sub_rest), _ = rest
            if sub_kind == Nodetype.BASE and sub_rest[0] in numpy_types:
                kwargs[name] = np.array(value, dtype=numpy_types[sub_rest[0]])
            elif sub_kind == Nodetype.BASE:
                kwargs[name] = list(value)
            else:
                kwargs[name] = [to_rosbags(store, sub_rest, v) for v in value]
    return store.types[typename](**kwargs)
