"""`composuite session`: the recorded headless session, end to end. Two tasks (set_task between
them) × episodes with a built-in policy over ROS 2; the table it writes equals the one
`composuite bag episodes` recomputes from the bag, and the one this test recomputes from the bag
with `rosbags`; every observation matched the in-process environment (else it exits non-zero).

Only run inside scripts/netns-isolate."""

import csv
import json
import subprocess

import node_suite
from test_recorder import bag_messages

TASKS = ["IIWA/box/no_obstacle/pick_place", "Gen3/plate/object_wall/push"]


def session(*args: str) -> subprocess.CompletedProcess:
    node_suite.require_isolation()
    return subprocess.run([str(node_suite.node_dir() / "composuite"), "session", *args],
                          capture_output=True, text=True, timeout=600)


def test_a_two_task_session_writes_a_bag_and_a_table_that_agree(tmp_path):
    out = tmp_path / "s"
    result = session("--tasks", *TASKS, "--episodes", "2", "--policy", "random", "--horizon", "40",
                     "--seed", "7", "--out", str(out))
    assert result.returncode == 0, result.stderr[-4000:]
    # Not a terminal: one progress line per episode.
    assert result.stderr.count("episode ") >= 4 and "steps/s" in result.stderr
    rows = list(csv.DictReader((out / "episodes.csv").open()))
    assert [(r["task"], r["seed"], r["length"]) for r in rows] == [
        (t, str(s), "40") for t in TASKS for s in (7, 8)]
    assert json.loads((out / "episodes.json").read_text())[0]["task"] == TASKS[0]
    from_bag = subprocess.run([str(node_suite.node_dir() / "composuite"), "bag", "episodes", str(out / "bag"),
                               "--csv", str(tmp_path / "from_bag.csv")], capture_output=True, text=True)
    assert from_bag.returncode == 0, from_bag.stderr
    assert (tmp_path / "from_bag.csv").read_text() == (out / "episodes.csv").read_text()
    # The same table, recomputed here from the bag with rosbags.
    recorded = bag_messages(out / "bag")
    (topic,) = [t for t in recorded if t.endswith("/episode")]
    last: dict[int, object] = {}
    for _, status in recorded[topic]:
        last[status.episode] = status
    ours = [(s.task.robot + "/" + s.task.object + "/" + s.task.obstacle + "/" + s.task.objective, str(s.seed),
             str(s.step), repr(s.episode_return)) for _, s in sorted(last.items())]
    assert ours == [(r["task"], r["seed"], r["length"], r["return"]) for r in rows]
    commands = [t for t in recorded if t.endswith("/joint_command")]
    assert len(recorded[commands[0]]) == 4 * 40, "every command the agent sent is in the bag"


def test_the_expert_session_succeeds(tmp_path):
    result = session("--episodes", "1", "--horizon", "200", "--out", str(tmp_path / "e"), "--json")
    assert result.returncode == 0, result.stderr[-4000:]
    (row,) = json.loads(result.stdout)
    assert row["success"] and row["length"] == 200 and row["furthest_stage"] >= 3


def test_bad_session_arguments_are_named(tmp_path):
    result = session("--policy", "clever", "--out", str(tmp_path / "x"))
    assert result.returncode == 2 and "valid: expert, random, zero" in result.stderr
    result = session("--tasks", "IIWA/cube/no_obstacle/push", "--out", str(tmp_path / "y"))
    assert result.returncode == 2 and "--tasks" in result.stderr
    (tmp_path / "z").mkdir()
    result = session("--out", str(tmp_path / "z"))
    assert result.returncode == 2 and "exists already" in result.stderr
