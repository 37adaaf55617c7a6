"""The offline benchmark's `expert` and `medium` types: the planned expert acting in the
reference's action space, its files re-simulating bit for bit; `medium` the same expert with
Gaussian noise on its joint values, the noise taken from the calibration table shipped with the
suite (each of whose entries must still measure what the table says — a table left behind by a
change of physics or expert fails here), or calibrated for a task the table lacks."""

from __future__ import annotations

import json
import subprocess
import sys

import h5py
import numpy as np
import pytest

from composuite_ros import datasets
from composuite_ros.datasets import medium

EASY = "IIWA/box/no_obstacle/pick_place"
EASY_FOLDER = "IIWA_Box_None_PickPlace"


def cli(*args: str) -> subprocess.CompletedProcess:
    return subprocess.run([sys.executable, "-m", "composuite_ros.datasets.cli", *args],
                          capture_output=True, text=True)


def test_expert_files_succeed_and_replay_bit_for_bit(tmp_path):
    tasks = datasets.select_tasks([EASY])
    [path] = datasets.generate(tmp_path, tasks, ["expert"], transitions=1000, threads=2,
                               command="test")
    assert path == tmp_path / "expert" / EASY_FOLDER / "data.hdf5"
    with h5py.File(path) as f:
        assert f.attrs["policy"] == "expert"
        settings = json.loads(f.attrs["policy_settings"])
        assert settings["noise"] == 0.0
        assert settings["expert_revision"] == medium.EXPERT_REVISION >= 1
        starts, successes = f["episode_starts"][:], f["successes"][:]
        assert list(starts) == [0, 500]
        # Both episodes succeed: the expert solves this task on seeds 0 and 1.
        assert np.maximum.reduceat(successes, starts).tolist() == [1, 1]
        actions = f["actions"][:]
        assert (np.abs(actions) <= 1).all()
        assert set(np.unique(actions[:, 7])) <= {-1.0, 0.0, 1.0}
    verdict = datasets.verify(path, threads=2)
    assert verdict.ok, verdict.difference
    assert datasets.open_task(path).episode_successes().tolist() == [True, True]
    info = cli("info", str(path))
    assert "episodes: 2, 2 with a success (100.0%)" in info.stdout, info


def shipped_table() -> medium.NoiseTable:
    return medium.NoiseTable.load(medium.TABLE)


def test_the_shipped_table_is_for_the_default_target_and_each_search_finished():
    table = shipped_table()
    assert table.target == medium.DEFAULT_TARGET and table.horizon == 500
    assert table.first_seed == medium.FIRST_SEED and len(table.tasks) >= 4
    for name, c in table.tasks.items():
        assert c.task == name and c.episodes == table.episodes
        if len(c.trials) == 1:
            # The expert itself not above the target: medium is the expert.
            assert c.noise == 0.0 and c.expert_success <= c.target + medium.TOLERANCE, c
            continue
        # The search ended on target, at an end of its range, or after every measurement it
        # may make; the noise chosen is the closest measurement to the target.
        last_noise, last_rate = c.trials[-1]
        assert (abs(last_rate - c.target) <= medium.TOLERANCE + 1e-9
                or last_noise in medium.NOISE_RANGE
                or len(c.trials) == medium.MAX_TRIALS + 1), c
        closest = min(c.trials[1:], key=lambda t: (abs(t[1] - c.target), t[0]))
        assert [c.noise, c.success] == closest, c


@pytest.mark.parametrize("name", ["IIWA/box/no_obstacle/pick_place", "IIWA/box/no_obstacle/push"])
def test_medium_measures_what_the_table_says(name):
    """The shipped noise, played again over the calibration's episodes, gives the table's
    success rate exactly, within 0.05 of the target."""
    table = shipped_table()
    c = table.tasks[name]
    assert c.current, (
        f"{name}'s noise was calibrated with expert revision {c.expert_revision}, the expert is "
        f"revision {medium.EXPERT_REVISION}: calibrate it again with composuite-dataset "
        f"calibrate-medium --tasks {name} --out <the shipped medium_noise.json>")
    rate = medium.success_rate(name, c.noise, episodes=c.episodes, first_seed=c.first_seed,
                               threads=2, horizon=c.horizon)
    assert rate == c.success
    assert abs(rate - medium.DEFAULT_TARGET) <= medium.TOLERANCE


def test_medium_files_take_the_tables_noise_and_replay(tmp_path):
    name = "IIWA/box/no_obstacle/push"
    noise = shipped_table().tasks[name].noise
    [path] = datasets.generate(tmp_path, datasets.select_tasks([name]), ["medium"],
                               transitions=700, threads=2, command="test")
    with h5py.File(path) as f:
        settings = json.loads(f.attrs["policy_settings"])
        assert settings["noise"] == noise and settings["target_success"] == 0.3
        assert settings["calibration_source"].startswith("table medium_noise.json")
    verdict = datasets.verify(path, threads=2)
    assert verdict.ok, verdict.difference
    # The same rows without noise are the expert's: the noise changed the actions.
    [expert] = datasets.generate(tmp_path / "e", datasets.select_tasks([name]), ["expert"],
                                 transitions=700, threads=2, command="test")
    with h5py.File(path) as noisy, h5py.File(expert) as clean:
        assert not np.array_equal(noisy["actions"][:], clean["actions"][:])
        assert np.array_equal(noisy["actions"][:, 7][:1], clean["actions"][:, 7][:1])


def test_calibrate_medium_writes_and_extends_a_table(tmp_path):
    """A small calibration (6 episodes a try) through the command: the table names the noise
    it found and the trials on the way; a target the table is not for is calibrated when its
    medium file is generated."""
    out = tmp_path / "table.json"
    done = cli("calibrate-medium", "--tasks", EASY, "--episodes", "6", "--out", str(out),
               "--threads", "2")
    assert done.returncode == 0, done.stderr
    assert f"{EASY}: noise" in done.stdout and "noise 0 -> success 1.00" in done.stderr
    table = medium.NoiseTable.load(out)
    c = table.tasks[EASY]
    assert (table.episodes, c.expert_success, c.trials[0]) == (6, 1.0, [0.0, 1.0])
    assert c.noise > 0 and [c.noise, c.success] in c.trials
    assert table.provenance["command"].startswith("composuite-dataset calibrate-medium")
    # Run again, the table's task is kept, not measured again.
    again = cli("calibrate-medium", "--tasks", EASY, "--episodes", "6", "--out", str(out))
    assert again.returncode == 0 and "already in" in again.stderr and "->" not in again.stderr
    assert medium.NoiseTable.load(out).tasks[EASY] == c
    [path] = datasets.generate(tmp_path / "d", datasets.select_tasks([EASY]), ["medium"],
                               transitions=500, threads=2, command="test",
                               target_success=0.6, medium_table=out)
    with h5py.File(path) as f:
        settings = json.loads(f.attrs["policy_settings"])
    assert settings["target_success"] == 0.6
    assert settings["calibration_source"] == "measured when this file was generated"
    # An entry measured with another revision of the expert's actions is not used, and the
    # next calibration replaces it.
    stale = medium.NoiseTable.load(out)
    stale.tasks[EASY].expert_revision = medium.EXPERT_REVISION + 1
    stale.tasks[EASY].noise = stale_noise = 0.37
    stale.save(out)
    notes = []
    calibration, source = medium.noise_for(datasets.select_tasks([EASY])[0], 0.3, 500,
                                           table=out, threads=2, episodes=6,
                                           progress=notes.append)
    assert source == "measured when this file was generated" and calibration.current
    assert f"measured with expert revision {medium.EXPERT_REVISION + 1}" in notes[0], notes
    # The search begins at the stale entry's noise (after the expert's own rate, unnoised).
    assert calibration.trials[1][0] == stale_noise, calibration.trials
    third = cli("calibrate-medium", "--tasks", EASY, "--episodes", "6", "--out", str(out))
    assert third.returncode == 0 and "calibrating it again" in third.stderr, third.stderr
    recalibrated = medium.NoiseTable.load(out).tasks[EASY]
    assert recalibrated.current and recalibrated.trials[1][0] == stale_noise


def test_bad_calibration_input_is_refused(tmp_path):
    done = cli("calibrate-medium", "--tasks", EASY, "--out", str(tmp_path / "t.json"),
               "--target-success", "0")
    assert done.returncode == 2 and "must lie strictly between 0 and 1" in done.stderr
    bad = tmp_path / "bad.json"
    bad.write_text("{}")
    done = cli("generate", "--out", str(tmp_path / "d"), "--tasks", EASY, "--types", "medium",
               "--medium-table", str(bad))
    assert done.returncode == 2
    assert "is not one `composuite-dataset calibrate-medium` wrote" in done.stderr
    assert not (tmp_path / "d").exists()
