"""The test suite's DDS traffic cannot leave this machine: pytest runs inside
scripts/netns-isolate, whose network namespace has only loopback, with multicast (what DDS
discovery uses) routed to it. Nothing here sends a packet before isolation is established."""

from __future__ import annotations

import errno
import os
import socket
import struct
import subprocess
import sys

import pytest

import msgcheck

GROUP = "239.255.0.1"  # the DDS default discovery group


def interfaces() -> list[str]:
    # Asked of the kernel for this process's namespace (/sys/class/net may show the host's).
    return sorted(name for _, name in socket.if_nameindex())


def test_only_loopback_exists():
    assert interfaces() == ["lo"], "run the tests through scripts/netns-isolate"


def test_no_route_leaves_the_machine():
    assert interfaces() == ["lo"]
    for address in ("192.0.2.1", "10.0.0.1", "8.8.8.8"):
        with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as s:
            # connect() on UDP only resolves the route; it sends nothing.
            with pytest.raises(OSError) as raised:
                s.connect((address, 7400))
            assert raised.value.errno == errno.ENETUNREACH, address


def test_multicast_is_delivered_on_loopback():
    assert interfaces() == ["lo"]
    receiver = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
    receiver.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
    receiver.bind(("", 0))
    port = receiver.getsockname()[1]
    membership = struct.pack("4s4s", socket.inet_aton(GROUP), socket.inet_aton("127.0.0.1"))
    receiver.setsockopt(socket.IPPROTO_IP, socket.IP_ADD_MEMBERSHIP, membership)
    receiver.settimeout(2.0)
    sender = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
    sender.setsockopt(socket.IPPROTO_IP, socket.IP_MULTICAST_IF, socket.inet_aton("127.0.0.1"))
    sender.sendto(b"discovery?", (GROUP, port))
    data, (source, _) = receiver.recvfrom(64)
    assert data == b"discovery?" and source == "127.0.0.1"
    sender.close()
    receiver.close()


def test_wrapper_makes_a_fresh_loopback_only_namespace():
    script = (
        "import os, socket; print(os.readlink('/proc/self/ns/net')); "
        "print(sorted(n for _, n in socket.if_nameindex()))"
    )
    out = subprocess.run(
        [str(msgcheck.REPO / "scripts/netns-isolate"), sys.executable, "-c", script],
        capture_output=True, text=True, check=True,
    ).stdout.splitlines()
    assert out[0] != os.readlink("/proc/self/ns/net")
    assert out[1] == "['lo']"
