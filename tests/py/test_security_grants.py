"""Least privilege on a secured graph: every node of the suite in an enclave of its own whose
permissions `composuite security create-enclave --grant NODE` generated from the suite's own
topic and service table (a topic missing from it would stop the node that needs it, under
Enforce), and an agent enclave (`--grant agent`) that may command one environment and no other.
The agent is the Fast DDS peer of test_security_fastdds.py: access control on both sides is
what the permissions say. Only run inside scripts/netns-isolate."""

from __future__ import annotations

import json
import os
import subprocess

import pytest

import node_suite
from test_security_fastdds import (  # noqa: F401  (peer: a fixture)
    floats, peer, peer_said, secured_launch)

COMPOSUITE = node_suite.node_dir() / "composuite"
TASK = "Gen3/hollow_box/object_wall/push"
NS = "/granted"
# Where the recorder's test runs its own suite (the module's suite keeps running in NS).
RECORDED_NS = "/recorded"
SEED = 5
STEPS = 12
NODES = ("task_manager", "sim", "reward")
# An sros2 policy (format 0.2.0) granting the Fast DDS agent exactly the endpoints it has.
POLICY = f"""<?xml version="1.0" encoding="UTF-8"?>
<policy version="0.2.0" xmlns:xi="http://www.w3.org/2001/XInclude">
  <enclaves>
    <enclave path="/from_policy">
      <profiles>
        <profile ns="{NS}" node="fastdds_agent">
          <xi:include href="common/node.xml" xpointer="xpointer(/profile/*)"/>
          <topics publish="ALLOW"><topic>joint_command</topic></topics>
          <topics subscribe="ALLOW">
            <topic>joint_states</topic><topic>observation</topic><topic>reward</topic>
          </topics>
          <services request="ALLOW"><service>reset</service></services>
        </profile>
      </profiles>
    </enclave>
  </enclaves>
</policy>
"""
RECORDED = ("observation", "reward", "scene")


@pytest.fixture(scope="module")
def domain() -> int:
    return node_suite.random_domain()


def create(*args: str, domain: int) -> None:
    done = subprocess.run([str(COMPOSUITE), "security", *args, "--domain-id", str(domain)],
                          capture_output=True, text=True)
    assert done.returncode == 0, done.stderr


@pytest.fixture(scope="module")
def keystore(tmp_path_factory, domain):
    """An enclave per node (/composuite/<node>, its own grant in NS), an agent of NS, and an
    agent of another environment."""
    ks = tmp_path_factory.mktemp("sros2_grants") / "keystore"
    create("create-keystore", str(ks), domain=domain)
    for node in (*NODES, "recorder"):
        create("create-enclave", str(ks), f"/composuite/{node}", "--grant", node,
               "--namespace", NS, RECORDED_NS, domain=domain)
    create("create-enclave", str(ks), "/agent", "--grant", "agent", "--namespace", NS,
           domain=domain)
    create("create-enclave", str(ks), "/elsewhere", "--grant", "agent", "--namespace",
           "/elsewhere", domain=domain)
    policy = ks.parent / "policy.xml"
    policy.write_text(POLICY)
    create("create-enclave", str(ks), "/from_policy", "--policy", str(policy), domain=domain)
    return ks


@pytest.fixture(scope="module")
def suite(tmp_path_factory, keystore, domain):
    """One environment under Enforce, each node in its own enclave (--node-enclaves)."""
    log = tmp_path_factory.mktemp("grants_suite") / "launch.log"
    with secured_launch(log, keystore, domain, NS, "--node-enclaves", "/composuite",
                        task=TASK) as running:
        yield running


def run_agent(peer, domain: int, enclave, steps: int):
    env = {k: v for k, v in os.environ.items() if not k.startswith("ROS_")}
    return subprocess.run([str(peer), "--domain", str(domain), "--namespace", NS, "--enclave",
                           str(enclave), "--seed", str(SEED), "--steps", str(steps)],
                          env=env, capture_output=True, text=True, timeout=120)


def test_nodes_in_their_own_enclaves_serve_an_agent_of_their_environment(peer, suite, keystore,
                                                                         domain):
    """Each node started under its generated grant (none was refused an endpoint), and the agent
    of NS plays an episode through them, every observation and reward bit for bit the in-process
    env's."""
    done = run_agent(peer, domain, keystore / "enclaves" / "agent", STEPS)
    process, text = suite
    assert done.returncode == 0, f"{peer_said(done.stderr)}\n---- suite ----\n{text()[-3000:]}"
    steps = [json.loads(line) for line in done.stdout.splitlines()][1:]
    commands = [{"joints": floats(s["command"]), "gripper": None} for s in steps[1:]]
    replay = node_suite.env_replay_run({"task": TASK, "seed": SEED, "commands": commands})
    assert [s["flat"] for s in steps] == [node_suite.float_bits(r["flat"]) for r in replay]
    assert [s["reward"] for s in steps[1:]] == node_suite.float_bits(
        [r["reward"] for r in replay[1:]])
    assert "not allowed" not in text().lower(), text()[-3000:]


def test_the_recorder_in_its_own_enclave_records_the_environment(keystore, domain, tmp_path):
    """`--record` with the recorder in its enclave (--grant recorder: it reads every topic,
    serves its parameters in the root namespace where launch runs it): it starts and subscribes
    to the environment's topics."""
    wanted = [f"recording {RECORDED_NS}/{t} " for t in RECORDED]
    with secured_launch(tmp_path / "launch.log", keystore, domain, RECORDED_NS,
                        "--node-enclaves", "/composuite", "--record", str(tmp_path / "bag"),
                        task=TASK, ready=wanted) as (process, text):
        assert "not allowed" not in text().lower(), text()[-3000:]


def test_an_agent_of_another_environment_cannot_command_this_one(peer, suite, keystore, domain):
    """The agent grant of /elsewhere names /elsewhere's topics only: Fast DDS refuses it a
    joint_command writer in NS."""
    done = run_agent(peer, domain, keystore / "enclaves" / "elsewhere", 1)
    assert done.returncode == 1
    assert f"not allowed to create a DataWriter to topic rt{NS}/joint_command" in done.stderr, \
        peer_said(done.stderr)


def test_an_agent_in_an_enclave_made_from_an_sros2_policy_plays(peer, suite, keystore, domain):
    """create-enclave --policy: the permissions an sros2 policy gives the agent's endpoints
    (relative names in the profile's namespace, a service it calls) let it play."""
    done = run_agent(peer, domain, keystore / "enclaves" / "from_policy", 3)
    process, text = suite
    assert done.returncode == 0, f"{peer_said(done.stderr)}\n---- suite ----\n{text()[-3000:]}"
    assert [json.loads(line).get("step") for line in done.stdout.splitlines()][1:] == [0, 1, 2, 3]
