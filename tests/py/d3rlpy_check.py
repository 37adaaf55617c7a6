"""Opt-in (scripts/test-d3rlpy; d3rlpy pulls in torch, several GB): `datasets.to_d3rlpy` gives
d3rlpy 2.x an `MDPDataset` with the files' episodes and transitions, and d3rlpy's BC trains on
it and acts in the environment's action space."""

from __future__ import annotations

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
