"""Opt-in (scripts/test-d3rlpy; d3rlpy pulls in torch, several GB): `datasets.to_d3rlpy` gives
d3rlpy 2.x an `MDPDataset` with the files' episodes and transitions, and d3rlpy's BC trains on
it and acts in the environment's action space; the book's worked example
(`examples/offline_bc.py`: expert data, BC, evaluation) runs end to end in small, under the
Gymnasium 1.0 that d3rlpy 2.8 pins."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import d3rlpy
import numpy as np

from composuite_ros import datasets


def test_to_d3rlpy_keeps_the_episodes_and_bc_fits_on_it(tmp_path):
    tasks = datasets.select_tasks(["IIWA/box/no_obstacle/push", "Jaco/plate/goal_wall/shelf"])
    datasets.generate(tmp_path, tasks, ["random"], transitions=130, horizon=50, command="t")
    data = datasets.load(tmp_path, "random")
    mdp = datasets.to_d3rlpy(data)
    # 130 rows a task, horizon 50: episodes of 50, 50 and 30 (cut: a timeout) in each.
    assert [len(e.rewards) for e in mdp.episodes] == [50, 50, 30] * 2
    # d3rlpy counts a transition per step that has a next observation: an episode ended by a
    # timeout (all six here) gives its last step none.
    assert mdp.transition_count == 260 - 6
    first = mdp.episodes[0]
    assert np.array_equal(first.observations, data.parts[0]["observations"][:50])
    assert np.array_equal(first.actions, data.parts[0]["actions"][:50])
    assert not first.terminated
    bc = d3rlpy.algos.BCConfig(batch_size=32).create(device="cpu:0")
    bc.fit(mdp, n_steps=20, n_steps_per_epoch=20, show_progress=False, save_interval=100,
           experiment_name="bc_check", with_timestamp=False, logger_adapter=d3rlpy.logging.NoopAdapterFactory())
    action = bc.predict(data.parts[0]["observations"][:4])
    assert action.shape == (4, 8) and np.isfinite(action).all()


def test_the_offline_bc_example_runs_end_to_end(tmp_path):
    example = Path(__file__).resolve().parents[2] / "examples" / "offline_bc.py"
    done = subprocess.run([sys.executable, str(example), "--out", str(tmp_path),
                           "--transitions", "1000", "--steps", "50", "--episodes", "2"],
                          capture_output=True, text=True, timeout=900)
    assert done.returncode == 0, done.stderr[-3000:]
    result = json.loads((tmp_path / "result.json").read_text())
    assert (result["rows"], result["episodes_in_data"], result["eval_episodes"]) == (1000, 2, 2)
    # The expert solves this task on the data's seeds and on the evaluation's.
    assert result["data_success"] == 1.0 and result["expert_success"] == 1.0
    assert 0.0 <= result["bc_success"] <= 1.0 and (tmp_path / "bc.d3").exists()
