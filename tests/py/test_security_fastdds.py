"""Secure ROS 2 against a DDS-Security implementation nobody here wrote: a C++ agent on stock
Fast DDS 2.9 (Debian 12's libfastrtps-dev, whose builtin PKI-DH, Access-Permissions and
AES-GCM-GMAC plugins rmw_fastrtps uses), joining as rmw_fastrtps joins from an SROS2 enclave
(tests/interop/fastdds_secure_peer/), plays a lockstep episode through a secured suite: every
step's observation and reward bit for bit equal to the in-process env. A Fast DDS participant
without credentials, or with an identity another CA signed, gets nothing from it; one whose
permissions grant no joint_command cannot command (Fast DDS refuses it the writer, reading the
permissions `composuite security` signed). A peer with two readers of one topic gets both fed,
and a composed secured suite (`--envs 2`, one participant) plays an episode in each environment.
Only run inside scripts/netns-isolate."""

from __future__ import annotations

import contextlib
import json
import os
import signal
import struct
import subprocess
import time
from pathlib import Path

import pytest

import node_suite

COMPOSUITE = node_suite.node_dir() / "composuite"
TASK = "Jaco/plate/goal_wall/trash_can"
NS = "/fd"
SEED = 21
STEPS = 40
CONTROL_PERIOD_NS = 50_000_000
# Without a match in this long, a peer is refused: an accepted one matches within a second.
REFUSED_WINDOW_S = 5.0


@pytest.fixture(scope="module")
def peer() -> Path:
    """The peer binary: $COMPOSUITE_FASTDDS_PEER, else built once per source version into the
    cache ($COMPOSUITE_CACHE, default ~/.cache/composuite-ros)."""
    if not os.environ.get("COMPOSUITE_FASTDDS_PEER") and not Path(
            "/usr/include/fastdds/dds/domain/DomainParticipant.hpp").is_file():
        pytest.fail("Fast DDS headers missing: scripts/debian-packages installs libfastrtps-dev")
    return node_suite.fastdds_peer()


@pytest.fixture(scope="module")
def domain() -> int:
    return node_suite.random_domain()


def create(*args: str, domain: int) -> None:
    subprocess.run([str(COMPOSUITE), "security", *args, "--domain-id", str(domain)],
                   check=True, capture_output=True)


@pytest.fixture(scope="module")
def keystore(tmp_path_factory, domain) -> Path:
    """The suite's enclave `/`; the peer's `/fastdds_peer` (the default grant); and
    `/fastdds_observer`, which may subscribe to everything and publish no rt/ topic of the suite."""
    ks = tmp_path_factory.mktemp("sros2_fastdds") / "keystore"
    create("create-keystore", str(ks), domain=domain)
    create("create-enclave", str(ks), "/", domain=domain)
    create("create-enclave", str(ks), "/fastdds_peer", domain=domain)
    create("create-enclave", str(ks), "/fastdds_observer", "--allow-publish", "rq/*", "rr/*",
           "rt/rosout", "rt/parameter_events", "--allow-subscribe", "*", domain=domain)
    return ks


@contextlib.contextmanager
def secured_launch(log: Path, keystore: Path, domain: int, namespace: str, *extra: str,
                   task: str = TASK, ready: tuple[str, ...] = ()):
    """`composuite launch` (Enforce, enclave `/` unless `extra` says otherwise, services in
    rmw_fastrtps' format) until every node of every environment said it is up and the log shows
    each of `ready`; yields (process, the log's text); stopped after."""
    env = {k: v for k, v in os.environ.items() if not k.startswith("ROS_")}
    env.update(ROS_DOMAIN_ID=str(domain), ROS_SECURITY_ENABLE="true",
               ROS_SECURITY_STRATEGY="Enforce", ROS_SECURITY_KEYSTORE=str(keystore))
    envs = int(extra[extra.index("--envs") + 1]) if "--envs" in extra else 1
    namespaces = [namespace] if envs == 1 else [f"{namespace}/env_{i:02}" for i in range(envs)]
    with open(log, "wb") as out:
        process = subprocess.Popen(
            [str(COMPOSUITE), "launch", "--task", task, "--namespace", namespace,
             "--service-mapping", "fastdds", "--log-level", "info", *extra],
            env=env, stdin=subprocess.DEVNULL, stdout=out, stderr=out)
    text = lambda: log.read_text(errors="replace")
    try:
        deadline = time.monotonic() + 30
        while not (all(f"{ns}/{node} up" in text() for ns in namespaces
                       for node in node_suite.NODES)
                   and all(r in text() for r in ready)):
            assert process.poll() is None, text()[-4000:]
            assert time.monotonic() < deadline, text()[-4000:]
            time.sleep(0.05)
        yield process, text
    finally:
        process.send_signal(signal.SIGINT)
        try:
            code = process.wait(timeout=20)
        except subprocess.TimeoutExpired:
            process.kill()
            code = process.wait()
    assert code == 0, f"launch exited {code}:\n{text()[-4000:]}"


@pytest.fixture(scope="module")
def suite(tmp_path_factory, keystore, domain):
    """One environment, all three nodes secured (Enforce) with the `/` enclave, services in
    rmw_fastrtps' format."""
    log = tmp_path_factory.mktemp("fastdds_suite") / "launch.log"
    with secured_launch(log, keystore, domain, NS) as launched:
        yield launched


def run_peer(peer: Path, domain: int, *args: str, timeout: float = 120, namespace: str = NS):
    env = {k: v for k, v in os.environ.items() if not k.startswith("ROS_")}
    return subprocess.run([str(peer), "--domain", str(domain), "--namespace", namespace, *args],
                          env=env, capture_output=True, text=True, timeout=timeout)


def peer_said(stderr: str, tail: int = 2500) -> str:
    """The peer's stderr for a failure message: its own lines (`peer: ...`: which participants
    it authenticated, why it failed) in full, then the end of the rest — Fast DDS's key-exchange
    warnings would otherwise push them out of any tail."""
    own = [line for line in stderr.splitlines() if line.startswith("peer: ")]
    return "\n".join(own) + "\n---- peer's last output ----\n" + stderr[-tail:]


def floats(hexes: list[str]) -> list[float]:
    return [struct.unpack("<d", bytes.fromhex(h))[0] for h in hexes]


def test_a_fastdds_peer_plays_a_secured_episode_bit_for_bit(peer, suite, keystore, domain):
    """The peer authenticates with the suite's participants (PKI-DH), is checked against the
    signed governance and permissions both ways, exchanges AES-GCM keys, then resets with a seed
    and sends STEPS joint commands: each step's observation (all 93 values) and reward total
    equal, bit for bit, the in-process env given the same seed and commands."""
    done = run_peer(peer, domain, "--enclave", str(keystore / "enclaves" / "fastdds_peer"),
                    "--seed", str(SEED), "--steps", str(STEPS))
    process, text = suite
    assert done.returncode == 0, f"{peer_said(done.stderr)}\n---- suite ----\n{text()[-4000:]}"
    assert_episode_bit_for_bit(done.stdout, SEED, STEPS)
    assert process.poll() is None, text()[-4000:]


def assert_episode_bit_for_bit(stdout: str, seed: int, steps_played: int) -> None:
    """The peer's JSON lines: a head, then the reset state and each step, every observation and
    reward equal, bit for bit, to the in-process env's given the same seed and commands."""
    lines = [json.loads(line) for line in stdout.splitlines()]
    head, steps = lines[0], lines[1:]
    assert head["seed"] == seed and len(head["arm"]) == 7
    assert [s["step"] for s in steps] == list(range(steps_played + 1))
    stamps = [s["stamp_ns"] for s in steps]
    assert [b - a for a, b in zip(stamps, stamps[1:])] == [CONTROL_PERIOD_NS] * steps_played
    assert [s["reward_stamp_ns"] for s in steps[1:]] == stamps[1:]

    commands = [{"joints": floats(s["command"]), "gripper": None} for s in steps[1:]]
    replay = node_suite.env_replay_run({"task": TASK, "seed": seed, "commands": commands})
    assert len(replay) == steps_played + 1
    for step, (got, want) in enumerate(zip(steps, replay)):
        assert got["flat"] == node_suite.float_bits(want["flat"]), f"observation of step {step}"
    assert [s["reward"] for s in steps[1:]] == node_suite.float_bits(
        [r["reward"] for r in replay[1:]])


def test_a_fastdds_peer_without_credentials_gets_nothing(peer, suite, domain):
    """Security off on the peer: the suite's participants do not talk to an unauthenticated one
    (the governance allows none), so none of its endpoints match and no sample arrives."""
    done = run_peer(peer, domain, "--expect-no-suite", str(REFUSED_WINDOW_S))
    assert done.returncode == 0, done.stdout + peer_said(done.stderr)
    assert json.loads(done.stdout) == {"matched": 0, "observations": 0, "joint_states": 0}


def test_a_fastdds_peer_another_ca_signed_gets_nothing(peer, suite, tmp_path, domain):
    """A well-formed enclave of another keystore: its certificate does not chain to the suite's
    identity CA, so authentication fails and nothing matches."""
    other = tmp_path / "other_keystore"
    create("create-keystore", str(other), domain=domain)
    create("create-enclave", str(other), "/fastdds_peer", domain=domain)
    done = run_peer(peer, domain, "--enclave", str(other / "enclaves" / "fastdds_peer"),
                    "--expect-no-suite", str(REFUSED_WINDOW_S))
    assert done.returncode == 0, done.stdout + peer_said(done.stderr)
    assert json.loads(done.stdout)["matched"] == 0


def test_a_fastdds_peer_without_joint_command_permission_cannot_command(peer, suite, keystore,
                                                                        domain):
    """The /fastdds_observer enclave grants no rt/ publication: Fast DDS's own access control,
    reading the permissions `composuite security` signed, refuses the peer its joint_command
    writer, as RustDDS refuses the suite's own agent in test_security.py."""
    done = run_peer(peer, domain, "--enclave", str(keystore / "enclaves" / "fastdds_observer"),
                    "--seed", str(SEED), "--steps", "1", timeout=60)
    assert done.returncode == 1
    assert (f"rt{NS}/joint_command topic not found in allow rule" in done.stderr  # Fast DDS's
            and f"not allowed to create a DataWriter to topic rt{NS}/joint_command"
            in done.stderr), peer_said(done.stderr)


def test_a_fastdds_peer_with_two_readers_of_one_topic_gets_both_fed(peer, suite, keystore,
                                                                     domain):
    """Two subscriptions to `observation` in one participant (a ROS node with two, or two nodes
    of one context): both receive every step, and the episode still plays bit for bit. (RustDDS
    0.15.1's crypto plugin refused the second reader and its writer then reached neither: fix 11
    in third_party/README.md.)"""
    steps = 5
    done = run_peer(peer, domain, "--enclave", str(keystore / "enclaves" / "fastdds_peer"),
                    "--seed", str(SEED), "--steps", str(steps), "--second-observation-reader",
                    timeout=90)
    assert done.returncode == 0, peer_said(done.stderr)
    *episode, counts = done.stdout.splitlines()
    assert json.loads(counts)["second_reader_observations"] >= steps + 1
    assert_episode_bit_for_bit("\n".join(episode), SEED, steps)


def test_a_composed_secured_suite_plays_an_episode_in_each_environment(peer, keystore, domain,
                                                                      tmp_path):
    """`composuite launch --envs 2`: both environments' nodes in one process, one participant
    with the `/` enclave, whose own endpoints RustDDS matches through its crypto plugin like a
    remote participant's (each environment's `scene` has two readers there: fix 11). A peer in
    each environment's namespace, at the same time, plays an episode bit for bit."""
    namespace, steps = "/fdc", 10
    with secured_launch(tmp_path / "launch.log", keystore, domain, namespace,
                        "--envs", "2") as (process, text):
        env = {k: v for k, v in os.environ.items() if not k.startswith("ROS_")}
        peers = [subprocess.Popen(
            [str(peer), "--domain", str(domain), "--namespace", f"{namespace}/env_{i:02}",
             "--enclave", str(keystore / "enclaves" / "fastdds_peer"),
             "--seed", str(SEED + i), "--steps", str(steps)],
            env=env, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
            for i in range(2)]
        outputs = [p.communicate(timeout=120) for p in peers]
        for i, (p, (out, err)) in enumerate(zip(peers, outputs)):
            assert p.returncode == 0, f"env {i}: {err[-3000:]}\n---- suite ----\n{text()[-4000:]}"
            assert_episode_bit_for_bit(out, SEED + i, steps)
        assert process.poll() is None, text()[-4000:]
