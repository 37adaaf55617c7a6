"""The suite on one host, its agents on another: two network namespaces joined by a veth pair with
a 1500-byte MTU (scripts/netns-pair), as two machines on a LAN. Discovery crosses a real link,
and every sample over 1,452 bytes — a `reset` reply with its step-0 observation — is fragmented
into DATA_FRAGs, as between machines (on loopback, 64 kB MTU, it goes out whole).

The interop modules run again on host b against nodes started on host a
(COMPOSUITE_SUITE_NETNS tells node_suite where to start them), unchanged: the cyclonedds agent
(test_nodes_cyclone.py: set_task, reset, 500 lockstep steps bit-identical to the in-process
reference, bad input, sample_tasks), the real rclpy agent on Fast DDS (test_nodes_rclpy.py:
graph, services, a lockstep episode, parameters), and four environments of one launch with a
vector of agents (test_many_envs.py). While the cyclonedds module runs, rtps_capture.py checks
every DATA_FRAG host a sends with a parser of its own.

Then the link is made lossy (nftables drops 1 % of the datagrams each way) and a lockstep run must
still complete every step; a 20 ms delay needs the kernel's netem qdisc.

Needs root (named network namespaces); run inside scripts/netns-isolate like every DDS test."""

from __future__ import annotations

import json
import os
import re
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

import node_suite

REPO = Path(__file__).resolve().parents[2]
PAIR = REPO / "scripts" / "netns-pair"
HERE = Path(__file__).resolve().parent
HOST_A_ADDRESS = "198.18.0.1"
# RustDDS' datagram budget for a peer behind a 1500-byte MTU: larger samples are fragmented.
DATAGRAM_BUDGET = 1452


@pytest.fixture(scope="module")
def pair():
    node_suite.require_isolation()
    if os.geteuid() != 0:
        pytest.skip("two-host tests need root: scripts/netns-pair creates named network namespaces")
    name = f"cs{os.getpid() % 100_000}"
    subprocess.run([str(PAIR), "up", name], check=True, capture_output=True, text=True)
    yield name
    subprocess.run([str(PAIR), "down", name], check=False)


def on_host_b(pair: str, *command: str, timeout: float) -> subprocess.CompletedProcess:
    env = dict(os.environ, **{node_suite.SUITE_NETNS_VAR: f"{pair}-a"})
    return subprocess.run([str(PAIR), "exec", pair, "b", *command], env=env, cwd=HERE,
                          capture_output=True, text=True, timeout=timeout)


def pytest_on_host_b(pair: str, module: str) -> int:
    """Run a test module on host b against a suite on host a; the number of tests that passed."""
    result = on_host_b(pair, sys.executable, "-m", "pytest", "-p", "no:cacheprovider", "-q", module,
                       timeout=900)
    assert result.returncode == 0, f"{module} on host b:\n{result.stdout[-8000:]}\n{result.stderr[-3000:]}"
    summary = result.stdout.strip().splitlines()[-1]
    assert "skipped" not in summary and "deselected" not in summary, summary
    return int(re.search(r"(\d+) passed", summary).group(1))


def count_tests(module: str) -> int:
    return len(re.findall(r"^def test_", (HERE / module).read_text(), flags=re.MULTILINE))


class Capture:
    """rtps_capture.py on host b's end of the link, for the `with` body; `.summary` after."""

    def __init__(self, pair: str):
        self.process = subprocess.Popen(
            [str(PAIR), "exec", pair, "b", sys.executable, str(HERE / "rtps_capture.py"),
             "--interface", "veth-b", "--source", HOST_A_ADDRESS],
            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
        self.summary: dict = {}

    def __enter__(self) -> Capture:
        line = self.process.stderr.readline()
        assert "capturing" in line, line + self.process.stderr.read()
        return self

    def __exit__(self, *exc) -> None:
        self.process.send_signal(signal.SIGINT)
        out, err = self.process.communicate(timeout=10)
        assert self.process.returncode == 0, err
        self.summary = json.loads(out)


def assert_fragments_well_formed(summary: dict) -> None:
    assert summary["rtps"] > 0, summary
    assert summary["malformed_count"] == 0, summary["malformed"]
    # Service replies (inline QoS: the related sample identity) larger than a datagram did cross
    # the link as DATA_FRAGs, and every one of them parsed.
    assert summary["data_frags_with_inline_qos"] > 0, summary
    assert max(summary["inline_qos_sample_sizes"]) > DATAGRAM_BUDGET, summary


def test_the_pair_is_two_hosts_with_an_ethernet_mtu_and_no_way_out(pair):
    for host, address, peer in (("a", "198.18.0.1", "198.18.0.2"), ("b", "198.18.0.2", "198.18.0.1")):
        link = subprocess.run([str(PAIR), "exec", pair, host, "ip", "-o", "link", "show", f"veth-{host}"],
                              capture_output=True, text=True, check=True).stdout
        assert "mtu 1500" in link and "MULTICAST" in link, link
        routes = subprocess.run([str(PAIR), "exec", pair, host, "ip", "route"],
                                capture_output=True, text=True, check=True).stdout
        assert "default" not in routes and "224.0.0.0/4" in routes, routes
        addresses = subprocess.run([str(PAIR), "exec", pair, host, "ip", "-o", "-4", "addr"],
                                   capture_output=True, text=True, check=True).stdout
        assert address in addresses and peer not in addresses


def test_cyclonedds_agent_on_host_b_runs_the_interop_module(pair):
    with Capture(pair) as capture:
        passed = pytest_on_host_b(pair, "test_nodes_cyclone.py")
    assert passed >= count_tests("test_nodes_cyclone.py")
    assert_fragments_well_formed(capture.summary)


def test_rclpy_agent_on_host_b_runs_the_interop_module(pair):
    with Capture(pair) as capture:
        passed = pytest_on_host_b(pair, "test_nodes_rclpy.py")
    assert passed == count_tests("test_nodes_rclpy.py")
    assert_fragments_well_formed(capture.summary)


def test_four_environments_on_host_a_and_their_agents_on_host_b(pair):
    assert pytest_on_host_b(pair, "test_many_envs.py") == count_tests("test_many_envs.py")


def lockstep_run(pair: str, steps: int) -> dict:
    result = on_host_b(pair, sys.executable, str(HERE / "bench_lockstep.py"),
                       "--composuite", str(node_suite.node_dir() / "composuite"), "--steps", str(steps),
                       "--tasks", "IIWA/box/no_obstacle/pick_place", "--json", timeout=600)
    assert result.returncode == 0, result.stderr[-5000:]
    (run,) = json.loads(result.stdout)
    print(f"two hosts: {run}")
    return run


def test_lockstep_completes_every_step_when_the_link_drops_1_percent(pair):
    subprocess.run([str(PAIR), "loss", pair, "1"], check=True)
    try:
        run = lockstep_run(pair, 1000)
    finally:
        subprocess.run([str(PAIR), "loss", pair, "0"], check=True)
    assert run["steps"] == 1000  # every step's observation and reward arrived (reliable QoS)


def test_lockstep_completes_every_step_over_a_20_ms_link(pair):
    added = subprocess.run([str(PAIR), "exec", pair, "a", "tc", "qdisc", "add", "dev", "veth-a", "root",
                            "netem", "delay", "20ms"], capture_output=True, text=True)
    if added.returncode != 0:
        pytest.skip(f"this kernel has no netem qdisc (`tc qdisc add ... netem`: {added.stderr.strip()}); "
                    "delay is not emulated here, loss is (nftables)")
    try:
        started = time.monotonic()
        run = lockstep_run(pair, 200)
    finally:
        subprocess.run([str(PAIR), "exec", pair, "a", "tc", "qdisc", "del", "dev", "veth-a", "root"])
    assert run["steps"] == 200
    # Every step crosses the delayed link at least once.
    assert time.monotonic() - started > 200 * 0.02
