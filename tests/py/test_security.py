"""Secure ROS 2 (SROS2): the suite joins a DDS-Security graph from a keystore `composuite
security` made — authenticated participants, encrypted discovery and data — and honours rcl's
switches (ROS_SECURITY_ENABLE, ROS_SECURITY_STRATEGY, ROS_SECURITY_KEYSTORE,
ROS_SECURITY_ENCLAVE_OVERRIDE, --enclave). Only run inside scripts/netns-isolate."""

from __future__ import annotations

import json
import os
import shutil
import signal
import socket
import subprocess
import threading
import time

import pytest

import node_suite
from rclpy_agent import RclpyAgent

COMPOSUITE = node_suite.node_dir() / "composuite"


@pytest.fixture(scope="module")
def domain() -> int:
    return node_suite.random_domain()


@pytest.fixture(scope="module")
def keystore(tmp_path_factory, domain):
    """A keystore whose governance and `/` enclave's permissions cover this module's domain
    (the documents name their domains: another one is refused, as DDS-Security requires)."""
    ks = tmp_path_factory.mktemp("sros2") / "keystore"
    # /observer may call services and read everything, and publish no ROS topic but the log.
    observer = ["--allow-publish", "rq/*", "rr/*", "rt/rosout", "rt/parameter_events",
                "--allow-subscribe", "*"]
    for args in (["create-keystore", str(ks)], ["create-enclave", str(ks), "/"],
                 ["create-enclave", str(ks), "/observer", *observer]):
        subprocess.run([str(COMPOSUITE), "security", *args, "--domain-id", str(domain)],
                       check=True, capture_output=True)
    return ks


def switches(keystore, domain: int, **extra: str) -> dict:
    """This process's environment without ROS settings, plus rcl's security switches (Enforce)."""
    env = {k: v for k, v in os.environ.items() if not k.startswith("ROS_")}
    env.update(ROS_DOMAIN_ID=str(domain), ROS_SECURITY_ENABLE="true",
               ROS_SECURITY_STRATEGY="Enforce", ROS_SECURITY_KEYSTORE=str(keystore))
    env.update(extra)
    return env


def test_a_secured_suite_plays_an_episode_bit_for_bit(keystore, domain):
    """`composuite demo` (the suite's three nodes and the expert agent, four participants) with
    every participant authenticated and discovery, liveliness and data encrypted: the episode
    equals the in-process env's."""
    done = subprocess.run([str(COMPOSUITE), "demo", "--episodes", "1", "--json"],
                          env=switches(keystore, domain),
                          capture_output=True, text=True, timeout=120)
    assert done.returncode == 0, done.stderr[-3000:]
    episode = json.loads(done.stdout.splitlines()[-1])
    assert episode["identical_to_in_process"] and episode["success"], episode


# Bytes of the samples themselves that go on the wire in clear in a plain session: the task's
# objective (set_task, the scene, the episode status) and a joint's name (joint_states,
# joint_command). (Topic and type names are not among them: RustDDS announces a secured
# endpoint in the plain endpoint discovery, signed but not encrypted — see the book.)
CLEAR_TEXT = (b"pick_place", b"l_finger_joint")


@pytest.mark.parametrize("secured", [False, True], ids=["plain", "secured"])
def test_nothing_readable_goes_on_the_wire_when_secured(keystore, domain, secured):
    """Every datagram on the namespace's loopback during a demo episode, captured with a packet
    socket: plain, the task's objective and a joint's name are there to read in the samples;
    secured (data encrypted, messages signed), neither is."""
    packets: list[bytes] = []
    stop = threading.Event()
    sniffer = socket.socket(socket.AF_PACKET, socket.SOCK_RAW, socket.ntohs(0x0003))
    sniffer.bind(("lo", 0))
    sniffer.settimeout(0.1)

    def capture():
        while not stop.is_set():
            try:
                packets.append(sniffer.recv(65535))
            except socket.timeout:
                pass

    thread = threading.Thread(target=capture)
    thread.start()
    env = switches(keystore, domain)
    if not secured:
        env = {k: v for k, v in env.items() if not k.startswith("ROS_SECURITY")}
    try:
        done = subprocess.run([str(COMPOSUITE), "demo", "--episodes", "1", "--json"], env=env,
                              capture_output=True, text=True, timeout=120)
    finally:
        stop.set()
        thread.join()
        sniffer.close()
    assert done.returncode == 0, done.stderr[-3000:]
    wire = b"".join(packets)
    assert len(packets) > 1000 and len(wire) > 200_000, (len(packets), len(wire))
    readable = [text for text in CLEAR_TEXT if text in wire]
    assert readable == ([] if secured else list(CLEAR_TEXT)), readable


def test_an_enclave_without_joint_command_cannot_command_the_sim(keystore, domain):
    """The same demo, its agent in an enclave whose permissions grant no rt/ publication: its
    joint_command writer is refused when it is created, and the demo stops saying so."""
    done = subprocess.run([str(COMPOSUITE), "demo", "--episodes", "1", "--json",
                           "--agent-enclave", "/observer"],
                          env=switches(keystore, domain), capture_output=True, text=True,
                          timeout=120)
    assert done.returncode == 2, done.stdout
    assert ("publisher joint_command" in done.stderr
            and "Not allowed to create a DataWriter to topic rt/demo_" in done.stderr), \
        done.stderr[-3000:]
    assert done.stdout == ""


def test_enforce_stops_a_node_whose_enclave_is_missing_and_permissive_warns(keystore, domain,
                                                                            tmp_path):
    node = [str(COMPOSUITE), "node", "sim", "--ros-args", "-r", "__ns:=/sec_missing"]
    env = switches(keystore, domain, ROS_SECURITY_ENCLAVE_OVERRIDE="/nobody")
    done = subprocess.run(node, env=env, capture_output=True, text=True, timeout=30)
    assert done.returncode == 2
    assert ("SECURITY ERROR: unable to find a folder matching the enclave '/nobody'"
            in done.stderr), done.stderr
    # Permissive: the node warns, joins without security, and runs (until stopped).
    log = tmp_path / "permissive.log"
    env["ROS_SECURITY_STRATEGY"] = "Permissive"
    with open(log, "wb") as out:
        process = subprocess.Popen(node, env=env, stdout=out, stderr=out)
    try:
        deadline = time.monotonic() + 20
        while "/sec_missing/sim up" not in log.read_text(errors="replace"):
            assert process.poll() is None, log.read_text()
            assert time.monotonic() < deadline, log.read_text()
            time.sleep(0.05)
    finally:
        process.send_signal(signal.SIGINT)
        process.wait(timeout=15)
    assert "joining WITHOUT security" in log.read_text()


def spoiled_enclave(keystore, domain: int, tmp_path, how: str):
    """A copy of the keystore whose `/` enclave is spoiled `how`: a signed document changed, an
    identity certificate from another keystore, or a certificate that has expired."""
    spoiled = tmp_path / f"keystore-{how}"
    shutil.copytree(keystore, spoiled, symlinks=True)
    enclave = spoiled / "enclaves"
    if how in ("governance", "permissions"):
        document = enclave / f"{how}.p7s"
        document.write_text(document.read_text().replace("<domains>", "<domains> ", 1))
    elif how == "foreign":
        other = tmp_path / "other-keystore"
        for args in (["create-keystore", str(other)], ["create-enclave", str(other), "/"]):
            subprocess.run([str(COMPOSUITE), "security", *args, "--domain-id", str(domain)],
                           check=True, capture_output=True)
        for name in ("cert.pem", "key.pem"):
            (enclave / name).write_bytes((other / "enclaves" / name).read_bytes())
    else:
        for name in ("cert.pem", "key.pem", "permissions.xml", "permissions.p7s"):
            (enclave / name).unlink()
        subprocess.run([str(COMPOSUITE), "security", "create-enclave", str(spoiled), "/",
                        "--domain-id", str(domain), "--days", "0"],
                       check=True, capture_output=True)
    return spoiled


@pytest.mark.parametrize("how,says", [
    ("governance", "governance.p7s: its signature does not verify"),
    ("permissions", "permissions.p7s: its signature does not verify"),
    ("foreign", "cert.pem is not signed by this keystore's identity CA"),
    ("expired", "cert.pem expired on"),
])
@pytest.mark.parametrize("strategy", ["Enforce", "Permissive"])
def test_a_node_with_spoiled_security_files_stops_saying_which_and_why(keystore, domain, tmp_path,
                                                                      how, says, strategy):
    """Files that are there but unusable stop the node at start-up under either strategy (the
    permissive one forgives only missing files), naming the file and what is wrong with it."""
    spoiled = spoiled_enclave(keystore, domain, tmp_path, how)
    env = switches(spoiled, domain, ROS_SECURITY_STRATEGY=strategy)
    done = subprocess.run([str(COMPOSUITE), "node", "sim", "--ros-args", "-r", "__ns:=/spoiled"],
                          env=env, capture_output=True, text=True, timeout=30)
    assert done.returncode == 2, done.stderr[-3000:]
    assert f"SECURITY ERROR: enclave /: {spoiled}/enclaves/{says}" in done.stderr, done.stderr
    assert "/spoiled/sim up" not in done.stderr


def test_a_participant_without_credentials_sees_none_of_the_suite(keystore, domain, tmp_path):
    """rclpy on Fast DDS (the PyPI wheels have no security plugins) on the same domain as a
    secured suite and an open one: it sees the open suite's topics and services, and none of
    the secured one's — those participants do not talk to an unauthenticated one."""
    suites = {}
    for namespace, env in (("/secured", switches(keystore, domain)),
                           ("/open", {k: v for k, v in os.environ.items()
                                      if not k.startswith("ROS_")} | {"ROS_DOMAIN_ID": str(domain)})):
        log = tmp_path / f"{namespace[1:]}.log"
        with open(log, "wb") as out:
            suites[namespace] = (log, subprocess.Popen(
                [str(COMPOSUITE), "launch", "--namespace", namespace, "--service-mapping",
                 "fastdds"], env=env, stdout=out, stderr=out))
    agent = None
    try:
        for namespace, (log, process) in suites.items():
            deadline = time.monotonic() + 30
            while f"{namespace}/reward up" not in log.read_text(errors="replace"):
                assert process.poll() is None, log.read_text()[-3000:]
                assert time.monotonic() < deadline, log.read_text()[-3000:]
                time.sleep(0.05)
        agent = RclpyAgent(domain)

        def seen(prefix: str) -> list[str]:
            names = agent.node.get_topic_names_and_types() + agent.node.get_service_names_and_types()
            return [name for name, _ in names if name.startswith(prefix)]

        agent.spin_until(lambda: "/open/reset" in seen("/open"), timeout=15,
                         what="the open suite's reset service")
        end = time.monotonic() + 2.0
        while time.monotonic() < end:
            agent.executor.spin_once(timeout_sec=0.1)
        assert seen("/secured") == [], seen("/secured")
        assert "/open/observation" in seen("/open")
    finally:
        if agent is not None:
            agent.close()
        for _, process in suites.values():
            process.send_signal(signal.SIGINT)
            process.wait(timeout=20)
