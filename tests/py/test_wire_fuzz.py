"""Bad input at the wire level: random, truncated and mangled RTPS datagrams sent to every port the
nodes of a running suite listen on (discovery and user traffic, multicast and unicast, by the
RTPS port formulas for the domain). No node may crash or stop answering: afterwards a reset and
a lockstep episode still give observations bit-identical to the in-process reference.

Only run inside scripts/netns-isolate (the datagrams go to loopback and its multicast group)."""

# No `from __future__ import annotations`: cyclonedds resolves annotations at runtime.
import random
import socket
import struct

import node_suite
from node_suite import env_replay_run, float_bits
from ros_agent import Agent, LockstepClient

DISCOVERY_GROUP = "239.255.0.1"
# RTPS 2.x well-known ports: PB + DG * domain (+ d1 for user multicast; + d0/d3 + PG * participant
# for discovery/user unicast).
PB, DG, PG, D0, D1, D2, D3 = 7400, 250, 2, 0, 1, 10, 11
PARTICIPANTS = range(8)
DATAGRAMS_PER_PORT = 1000
SUBMESSAGE_KINDS = [0x01, 0x06, 0x07, 0x08, 0x09, 0x0C, 0x0D, 0x0E, 0x12, 0x13, 0x15, 0x16, 0x00, 0xFF]


def rtps_header(rng: random.Random) -> bytes:
    return b"RTPS" + bytes([2, rng.choice([1, 3, 4, 5])]) + rng.randbytes(2) + rng.randbytes(12)


def submessage(rng: random.Random) -> bytes:
    kind = rng.choice(SUBMESSAGE_KINDS)
    flags = rng.randrange(256)
    body = rng.randbytes(rng.choice([0, 1, 3, 4, 8, 20, 28, 32, 60, 300]))
    declared = rng.choice([len(body), len(body) + 1, max(0, len(body) - 1), 0, 0xFFFF, rng.randrange(0x10000)])
    endian = "<" if flags & 1 else ">"
    return bytes([kind, flags]) + struct.pack(endian + "H", declared) + body


def datagram(rng: random.Random) -> bytes:
    """One of: random bytes; an RTPS header cut short; a header with random submessages (wrong
    lengths included); a header with a DATA_FRAG whose fragment fields are extreme."""
    choice = rng.randrange(4)
    if choice == 0:
        return rng.randbytes(rng.randrange(0, 1500))
    if choice == 1:
        return rtps_header(rng)[:rng.randrange(0, 20)]
    if choice == 2:
        return rtps_header(rng) + b"".join(submessage(rng) for _ in range(rng.randrange(1, 6)))
    body = (struct.pack("<HH", 0, rng.choice([0, 16, 28, 0xFFFF])) + rng.randbytes(16)
            + struct.pack("<IHHI", rng.choice([0, 1, 0xFFFFFFFF]), rng.choice([0, 1, 0xFFFF]),
                          rng.choice([0, 1, 256, 0xFFFF]), rng.choice([0, 1, 1 << 31, 0xFFFFFFFF]))
            + rng.randbytes(rng.randrange(0, 64)))
    return rtps_header(rng) + bytes([0x16, rng.choice([1, 3])]) + struct.pack("<H", len(body)) + body


def ports(domain: int) -> list[tuple[str, int]]:
    base = PB + DG * domain
    targets = [(DISCOVERY_GROUP, base + D0), (DISCOVERY_GROUP, base + D1)]
    for p in PARTICIPANTS:
        targets += [("127.0.0.1", base + D2 + PG * p), ("127.0.0.1", base + D3 + PG * p)]
    return targets


def bound_udp_ports() -> set[int]:
    """UDP ports something in this network namespace listens on (/proc/net is per namespace)."""
    ports = set()
    for table in ("/proc/net/udp", "/proc/net/udp6"):
        with open(table) as f:
            for line in f.readlines()[1:]:
                ports.add(int(line.split()[1].rsplit(":", 1)[1], 16))
    return ports


def test_garbage_datagrams_on_every_port_crash_no_node(tmp_path):
    domain = node_suite.random_domain()
    task = "Panda/dumbbell/goal_wall/shelf"
    with node_suite.running(tmp_path, "/fuzz", domain, task_manager={"service_mapping": "cyclone", "task": task}) \
            as suite:
        # The targets are real: the discovery port and each node's unicast ports are bound.
        listening = {port for _, port in ports(domain)} & bound_udp_ports()
        assert len(listening) >= 2 + 2 * 3, sorted(listening)
        rng = random.Random(20261124)
        sent = 0
        with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as out:
            out.setsockopt(socket.IPPROTO_IP, socket.IP_MULTICAST_TTL, 1)
            for address, port in ports(domain):
                for _ in range(DATAGRAMS_PER_PORT):
                    out.sendto(datagram(rng), (address, port))
                    sent += 1
        suite.assert_running()
        # Still answering, and still right.
        with Agent(namespace="/fuzz", domain_id=domain) as agent:
            client = LockstepClient(agent)
            reply = client.reset(seed=6)
            client.command.wait_for_subscribers(1, timeout=20)
            steps, commands = [reply.observation], []
            for k in range(1, 21):
                targets = [round(q + 0.01 * k, 6) for q in client.home]
                steps.append(client.step(targets, timeout=10, reward=False))
                commands.append({"joints": targets, "gripper": None})
        replay = env_replay_run({"task": task, "seed": 6, "commands": commands})
        assert [float_bits(o.flat) for o in steps] == [float_bits(r["flat"]) for r in replay]
        suite.assert_running()
    assert sent == len(ports(domain)) * DATAGRAMS_PER_PORT
