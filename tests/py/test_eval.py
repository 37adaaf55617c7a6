"""`composuite-eval` (the paper's evaluation protocol, composuite_ros.evaluate) against
`composuite launch --envs 2 --record`: the split equals `composuite tasks` (the reference's
sample_tasks), every episode runs once with its seed, and the printed R̄ and S̄ equal the ones
computed independently from the recorded bag and from the in-process Env."""

from __future__ import annotations

import csv
import json
import subprocess
import sys
from dataclasses import asdict

import numpy as np
import pytest

from node_suite import env_replay_run, launch_running, node_dir

import eval_agents
from composuite_ros import evaluate

HORIZON = 15
NAMESPACES = ["/ev/env_00", "/ev/env_01"]


@pytest.fixture(scope="module")
def suite(tmp_path_factory):
    folder = tmp_path_factory.mktemp("eval")
    with launch_running(folder, "/ev", "IIWA/box/no_obstacle/pick_place", "--envs", "2",
                        "--horizon", str(HORIZON), "--record", str(folder / "bag"),
                        service_mapping="fastdds") as launched:
        assert launched.namespaces == NAMESPACES
        launched.bag = folder / "bag"
        yield launched


def composuite_eval(*args: str, check: bool = True) -> subprocess.CompletedProcess:
    result = subprocess.run([sys.executable, "-m", "composuite_ros.evaluate", *args],
                            capture_output=True, text=True, timeout=300, check=False)
    if check:
        assert result.returncode == 0, result.stderr
    return result


def composuite_tasks(*args: str) -> list[str]:
    out = subprocess.run([str(node_dir() / "composuite"), "tasks", *args, "--json"],
                         capture_output=True, text=True, check=True).stdout
    return out


def test_native_and_ros_backends_give_the_same_table(suite):
    """One policy, two paths: the same agent, split and seeds in-process and over the suite give
    the same episodes and metrics, bit for bit (only where each episode ran differs)."""
    config = dict(experiment="smallscale", element="Jaco", num_train=3, split_seed=4, max_tasks=2,
                  episodes=2, seed=10, progress=False)
    ros_lists, ros_results, ros_rows = evaluate.evaluate(NAMESPACES, **config)
    lists, results, rows = evaluate.evaluate(backend="native", envs=3, horizon=HORIZON, **config)
    assert lists == ros_lists
    where = ("namespace", "episode")
    assert [{k: v for k, v in asdict(r).items() if k not in where} for r in results] == \
        [{k: v for k, v in asdict(r).items() if k not in where} for r in ros_results]
    assert {r.namespace for r in results} == {"native/0", "native/1", "native/2"}
    assert rows == ros_rows


def test_eval_metrics_equal_the_bag_and_the_in_process_env(suite, tmp_path):
    out = tmp_path / "out"
    result = composuite_eval("--experiment", "smallscale", "--element", "Jaco", "--num-train", "3",
                             "--split-seed", "4", "--max-tasks", "2", "--episodes", "2", "--seed", "10",
                             "--agent", "random", "--namespaces", ",".join(NAMESPACES), "--out", str(out))
    summary = json.loads((out / "summary.json").read_text())
    assert {p.name for p in out.iterdir()} >= {"episodes.csv", "summary.csv", "summary.json", "eval.png"}
    assert (out / "eval.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    # The split is the reference's: the same lists `composuite tasks` prints.
    reference = json.loads(composuite_tasks("--split", "smallscale", "--element", "Jaco",
                                            "--num-train", "3", "--seed", "4"))
    assert summary["tasks"]["train"] == reference["train"] and summary["tasks"]["test"] == reference["test"]
    episodes = summary["episodes"]
    chosen = reference["train"][:2] + reference["test"][:2]
    assert [(e["task"], e["seed"]) for e in episodes] == [(t, s) for t in chosen for s in (10, 11)]
    assert all(e["length"] == HORIZON for e in episodes)
    assert {e["namespace"] for e in episodes} == set(NAMESPACES), "both environments worked"

    # Each episode equals the in-process Env with the random agent's actions for that seed.
    for e in episodes:
        rng = np.random.default_rng(e["seed"])
        actions = [rng.uniform(-1, 1, size=8).tolist() for _ in range(HORIZON)]
        steps = env_replay_run({"task": e["task"], "seed": e["seed"], "horizon": HORIZON,
                                "commands": [{"reference": a} for a in actions]})
        rewards = [s["reward"] for s in steps[1:]]
        assert e["episode_return"] == sum(rewards), e
        assert e["success"] == any(r == 1.0 for r in rewards)

    # The bag of the same run, read by `composuite bag episodes`, gives the same R̄ and S̄.
    suite.stop()
    bag = json.loads(subprocess.run([str(node_dir() / "composuite"), "bag", "episodes", str(suite.bag),
                                     "--json"], capture_output=True, text=True, check=True).stdout)
    # Keyed by the task manager's episode numbers, which the evaluation reports.
    recorded = {(b["namespace"], b["suite_episode"]): b for b in bag}
    for e in episodes:
        b = recorded[(e["namespace"], e["episode"])]
        assert (b["task"], b["seed"], b["length"]) == (e["task"], e["seed"], e["length"])
        assert b["return"] == pytest.approx(e["episode_return"], abs=1e-12)
        assert b["success"] == e["success"]
    rows = {(m["split"], m["axis"], m["element"]): m for m in summary["metrics"]}
    for split, tasks in (("train", reference["train"][:2]), ("test", reference["test"][:2])):
        per_task = [np.mean([recorded[(e["namespace"], e["episode"])]["return"]
                             for e in episodes if e["task"] == t]) for t in tasks]
        success = [np.mean([recorded[(e["namespace"], e["episode"])]["success"]
                            for e in episodes if e["task"] == t]) for t in tasks]
        assert rows[(split, "all", "")]["mean_return"] == pytest.approx(np.mean(per_task), abs=1e-12)
        assert rows[(split, "all", "")]["success_rate"] == pytest.approx(np.mean(success), abs=1e-12)
        assert rows[(split, "robot", "Jaco")]["tasks"] == 2
    # The printed table carries the same numbers.
    assert f"{rows[('train', 'all', '')]['mean_return']:.3f}" in result.stdout
    with open(out / "summary.csv") as f:
        assert len(list(csv.DictReader(f))) == len(summary["metrics"])


def test_eval_with_a_user_agent_class(tmp_path):
    with launch_running(tmp_path, "/ua", "IIWA/box/no_obstacle/pick_place", "--horizon", "5",
                        service_mapping="fastdds"):
        eval_agents.ClosingGripper.resets.clear()
        lists, results, rows = evaluate.evaluate(["/ua"], experiment="default", num_train=2, split_seed=1,
                                                 splits=["train"], episodes=2, seed=3,
                                                 agent="eval_agents:ClosingGripper", progress=False)
    assert [r.task for r in results] == [t for t in lists["train"] for _ in range(2)]
    assert eval_agents.ClosingGripper.resets == [(t, s) for t in lists["train"] for s in (3, 4)]
    assert all(r.length == 5 for r in results)
    assert rows[0].split == "train" and rows[0].tasks == 2 and rows[0].episodes == 4


def test_native_eval_needs_no_suite(tmp_path):
    out = tmp_path / "native"
    result = composuite_eval("--experiment", "default", "--num-train", "2", "--split-seed", "1",
                             "--splits", "train", "--episodes", "2", "--horizon", "8", "--envs", "2",
                             "--quiet", "--out", str(out))
    summary = json.loads((out / "summary.json").read_text())
    reference = json.loads(composuite_tasks("--split", "default", "--num-train", "2", "--seed", "1"))
    assert summary["tasks"]["train"] == reference["train"]
    assert [(e["task"], e["seed"], e["length"]) for e in summary["episodes"]] == \
        [(t, s, 8) for t in reference["train"] for s in (0, 1)]
    assert summary["config"]["backend"] is None and "(all)" in result.stdout
    bad = composuite_eval("--envs", "0", check=False)
    assert bad.returncode == 2 and "--envs must be at least 1" in bad.stderr
    both = composuite_eval("--backend", "native", "--namespaces", "/a", check=False)
    assert both.returncode == 2 and "native backend runs its own environments" in both.stderr


def test_native_eval_of_named_tasks(tmp_path):
    """--tasks replaces the drawn split: the named tasks, in either spelling, are the train list."""
    out = tmp_path / "named"
    composuite_eval("--tasks", "IIWA/Box/None/PickPlace", "Jaco/plate/goal_wall/push",
                    "--episodes", "2", "--horizon", "6", "--envs", "2", "--quiet", "--out", str(out))
    summary = json.loads((out / "summary.json").read_text())
    assert summary["tasks"] == {"train": ["IIWA/box/no_obstacle/pick_place",
                                          "Jaco/plate/goal_wall/push"], "test": []}
    assert [(e["task"], e["seed"]) for e in summary["episodes"]] == \
        [(t, s) for t in summary["tasks"]["train"] for s in (0, 1)]
    bad = composuite_eval("--tasks", "IIWA/Box/Nne/PickPlace", check=False)
    assert bad.returncode == 2 and "'IIWA/Box/Nne/PickPlace' is not one of the 256" in bad.stderr


def test_eval_errors_are_clear(tmp_path):
    bad = composuite_eval("--agent", "no_such_module:Agent", "--timeout", "1", check=False)
    assert bad.returncode == 2 and "no_such_module" in bad.stderr
    nobody = composuite_eval("--namespaces", "/nobody", "--timeout", "1", check=False)
    assert nobody.returncode == 2 and "/nobody" in nobody.stderr and "Traceback" not in nobody.stderr
    usage = composuite_eval("--experiment", "huge", check=False)
    assert usage.returncode == 2 and "invalid choice" in usage.stderr
