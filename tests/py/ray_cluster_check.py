"""Opt-in (scripts/test-ray; needs Ray, which the default test venv does not install):
`composuite-dataset generate --ray` on a real two-node Ray cluster on loopback — the files equal
the ones written locally, bit for bit; a worker killed mid-shard is retried by Ray and its file
still comes out bit-identical; an address that does not answer is refused."""

from __future__ import annotations

import os
import signal
import socket
import subprocess
import sys
import time
from pathlib import Path

import h5py
import numpy as np
import pytest

from composuite_ros import datasets

TASKS = ["IIWA/box/no_obstacle/push", "Jaco/plate/object_wall/shelf",
         "Gen3/dumbbell/goal_wall/trash_can", "Panda/hollow_box/object_door/pick_place"]


def free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def ray(*args: str) -> None:
    subprocess.run([str(Path(sys.executable).parent / "ray"), *args], check=True,
                   capture_output=True, text=True, timeout=180)


@pytest.fixture(scope="module")
def cluster(tmp_path_factory):
    port = free_port()
    address = f"127.0.0.1:{port}"
    common = ["--node-ip-address", "127.0.0.1", "--num-cpus", "1", "--disable-usage-stats"]
    ray("start", "--head", "--port", str(port), "--include-dashboard=false", *common)
    try:
        ray("start", "--address", address, *common)
        yield address
    finally:
        ray("stop", "--force")


def generate_cli(out: Path, *args: str) -> subprocess.Popen:
    return subprocess.Popen([sys.executable, "-m", "composuite_ros.datasets.cli", "generate",
                             "--out", str(out), "--tasks", *TASKS, *args],
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)


def same_files(a: Path, b: Path) -> None:
    for task in datasets.select_tasks(TASKS):
        with h5py.File(datasets.task_file(a, "random", task)) as x, \
                h5py.File(datasets.task_file(b, "random", task)) as y:
            for key in ("observations", "actions", "rewards", "terminals", "timeouts",
                        "successes", "episode_starts", "episode_seeds",
                        "episode_final_observations"):
                assert np.array_equal(x[key][()], y[key][()]), (task.folder, key)


def test_shards_on_two_nodes_equal_the_local_files(cluster, tmp_path):
    import ray as ray_api
    ray_api.init(address=cluster, logging_level="ERROR")
    try:
        assert len([n for n in ray_api.nodes() if n["Alive"]]) == 2
    finally:
        ray_api.shutdown()
    args = ("--transitions", "700", "--horizon", "200", "--quiet")
    done = generate_cli(tmp_path / "ray", *args, "--ray", cluster)
    out, err = done.communicate(timeout=600)
    assert done.returncode == 0, err
    local = generate_cli(tmp_path / "local", *args)
    assert local.wait(timeout=600) == 0
    same_files(tmp_path / "ray", tmp_path / "local")


def test_a_worker_killed_mid_shard_is_retried_and_the_file_is_bit_identical(cluster, tmp_path):
    args = ("--transitions", "6000", "--quiet")
    done = generate_cli(tmp_path / "ray", *args, "--ray", cluster)
    killed = None
    deadline = time.monotonic() + 300
    while killed is None and time.monotonic() < deadline and done.poll() is None:
        partial = list((tmp_path / "ray").glob("random/*/data.hdf5.partial"))
        workers = subprocess.run(["pgrep", "-f", "ray::_shard_task"], capture_output=True,
                                 text=True).stdout.split()
        if partial and workers:
            os.kill(int(workers[0]), signal.SIGKILL)
            killed = int(workers[0])
        time.sleep(0.05)
    assert killed is not None, "no shard worker was seen running"
    out, err = done.communicate(timeout=900)
    assert done.returncode == 0, err
    local = generate_cli(tmp_path / "local", *args)
    assert local.wait(timeout=900) == 0
    same_files(tmp_path / "ray", tmp_path / "local")


def test_an_address_that_does_not_answer_is_refused(tmp_path):
    done = generate_cli(tmp_path / "d", "--transitions", "10", "--ray", f"127.0.0.1:{free_port()}")
    out, err = done.communicate(timeout=60)
    assert done.returncode == 2
    assert "does not answer" in err and "ray start --head" in err
