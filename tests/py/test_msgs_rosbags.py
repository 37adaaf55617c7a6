"""Our message layer against the `rosbags` library (an independent pure-Python ROS 2 CDR and
type-system implementation): byte-identical encodings both ways, equal decoded values, equal
RIHS01 hashes, and definition texts that `mcap_ros2` (another independent decoder) can use."""

from __future__ import annotations

import json
import random

import pytest

import msgcheck

SEED = 20261122
PER_TYPE = 25


@pytest.fixture(scope="module")
def store():
    return msgcheck.rosbags_store()


@pytest.fixture(scope="module")
def described():
    return json.loads(msgcheck.probe("describe"))


def test_every_rust_type_is_known_to_rosbags(store, described):
    missing = [name for name in described["messages"] if name not in store.fielddefs]
    assert not missing
    # and the field lists agree
    for name, info in described["messages"].items():
        assert [f for f, _ in store.fielddefs[name][1]] == info["fields"] or (
            info["fields"] == ["structure_needs_at_least_one_member"] and not store.fielddefs[name][1]
        ), name


def test_rust_encodings_are_byte_identical_to_rosbags(store, described):
    lines = msgcheck.probe_lines("random", str(SEED), str(PER_TYPE))
    assert len(lines) == PER_TYPE * len(described["messages"])
    for line in lines:
        name, ours = line["type"], bytes.fromhex(line["cdr"])
        decoded = store.deserialize_cdr(ours, name)
        assert msgcheck.canonical(store, name, decoded) == msgcheck.canonical(store, name, line["value"]), name
        assert bytes(store.serialize_cdr(decoded, name)) == ours, name


def test_rosbags_encodings_decode_and_reencode_identically_in_rust(store, described):
    rng = random.Random(SEED)
    sent = []
    for name in described["messages"]:
        for _ in range(PER_TYPE):
            plain = msgcheck.random_plain(store, rng, name)
            cdr = bytes(store.serialize_cdr(msgcheck.to_rosbags(store, name, plain), name))
            sent.append((name, plain, cdr))
    requests = "\n".join(json.dumps({"type": n, "cdr": c.hex()}) for n, _, c in sent)
    answers = msgcheck.probe_lines("roundtrip", stdin=requests)
    assert len(answers) == len(sent)
    for (name, plain, cdr), answer in zip(sent, answers):
        assert answer["ok"], f"{name}: {answer.get('error')}"
        assert bytes.fromhex(answer["cdr"]) == cdr, name
        assert msgcheck.canonical(store, name, answer["value"]) == msgcheck.canonical(store, name, plain), name


def test_garbage_from_python_is_an_error_not_a_crash(described):
    rng = random.Random(1)
    names = list(described["messages"])
    requests = []
    for i in range(400):
        junk = bytes(rng.getrandbits(8) for _ in range(rng.randrange(0, 64)))
        if i % 2:
            junk = b"\x00\x01\x00\x00" + junk
        requests.append(json.dumps({"type": names[i % len(names)], "cdr": junk.hex()}))
    answers = msgcheck.probe_lines("roundtrip", stdin="\n".join(requests))
    assert len(answers) == len(requests)
    assert sum(not a["ok"] for a in answers) > 200
    assert all(a["ok"] or a["error"] for a in answers)


def uses_char(store, name: str) -> bool:
    """Whether the type or anything it contains has a `char` field."""
    text = json.dumps(store.fielddefs[name][1], default=str)
    if '"char"' in text:
        return True
    return any(uses_char(store, n) for n in store.fielddefs if f'"{n}"' in text and n != name)


def test_type_hashes_equal_rosbags(store, described):
    skipped = []
    for name, info in described["messages"].items():
        if uses_char(store, name):
            # rosbags hashes `char` as type id 13; Jazzy's generator first turns a .msg char into
            # uint8 (id 3). Those types are checked against Jazzy's own output in the rclpy test.
            skipped.append(name)
            continue
        assert store.hash_rihs01(name) == info["type_hash"], name
    # Only service events hold a char (ServiceEventInfo's client_gid), and rcl_interfaces/Log.
    assert all(n.endswith("_Event") or n in ("service_msgs/msg/ServiceEventInfo", "rcl_interfaces/msg/Log")
               for n in skipped), skipped


def test_definitions_decode_our_bytes_in_mcap_ros2(store, described):
    """A reader that knows only the stored definition text (as Foxglove or mcap_ros2 do when
    reading a recording) decodes our bytes to the same values. Topics carry `msg` types only;
    rosbag2 stores service types differently, so the `srv` halves are not checked here."""
    from mcap_ros2._dynamic import generate_dynamic

    lines = msgcheck.probe_lines("random", str(SEED + 1), "5")
    decoders = {}
    checked = 0
    for line in lines:
        name = line["type"]
        if "/msg/" not in name:
            continue
        checked += 1
        if name not in decoders:
            decoders[name] = generate_dynamic(name, described["messages"][name]["definition"])[name]
        decoded = decoders[name](bytes.fromhex(line["cdr"]))
        assert msgcheck.canonical(store, name, decoded) == msgcheck.canonical(store, name, line["value"]), name
    assert checked == 5 * sum("/msg/" in n for n in described["messages"])
