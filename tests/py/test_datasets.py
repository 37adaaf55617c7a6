"""Offline datasets (`composuite_ros.datasets`, `composuite-dataset`): the authors' layout and
dtypes, read by a loader that behaves as the authors' `get_datasets` at the full 1,000,000 rows;
rows that are exactly what `CompoSuiteNative-v0` gives for the stored seeds and float32
actions; `verify` bit-exact and naming the first row that differs; the same file for 1 thread
and 2; memory-mapped multi-task reads; the Minari round trip with `recover_environment`; an
interrupted run that leaves no `data.hdf5` and `--resume`; bad input."""

from __future__ import annotations

import json
import os
import subprocess
import sys

import gymnasium
import h5py
import numpy as np
import pytest

import composuite_ros  # noqa: F401  (registers the envs)
from composuite_ros import datasets
from composuite_ros.datasets import DatasetError, DatasetWriter

HORIZON = 40
TASK = "IIWA/box/no_obstacle/push"
FOLDER = "IIWA_Box_None_Push"


def cli(*args: str, env: dict | None = None) -> subprocess.CompletedProcess:
    return subprocess.run([sys.executable, "-m", "composuite_ros.datasets.cli", *args],
                          capture_output=True, text=True, env=env)


@pytest.fixture(scope="module")
def generated(tmp_path_factory):
    """Two tasks of 100 rows, horizon 40: two whole episodes and a third cut at row 100."""
    root = tmp_path_factory.mktemp("data")
    tasks = datasets.select_tasks([TASK, "Gen3/Plate/ObjectWall/Shelf"])
    paths = datasets.generate(root, tasks, ["random"], transitions=100, horizon=HORIZON,
                              first_seed=3, threads=2, command="test")
    return root, paths


def test_layout_keys_and_dtypes_are_the_authors(generated):
    root, paths = generated
    assert [p.relative_to(root).as_posix() for p in paths] == [
        f"random/{FOLDER}/data.hdf5", "random/Kinova3_Plate_ObjectWall_Shelf/data.hdf5"]
    with h5py.File(paths[0]) as f:
        want = {"observations": ("float32", (100, 93)), "actions": ("float32", (100, 8)),
                "rewards": ("float32", (100,)), "terminals": ("uint8", (100,)),
                "timeouts": ("uint8", (100,)), "successes": ("uint8", (100,)),
                "episode_starts": ("int64", (3,)), "episode_seeds": ("uint64", (3,)),
                "episode_final_observations": ("float32", (3, 93))}
        assert {k: (str(f[k].dtype), f[k].shape) for k in f} == want
        assert list(f["episode_starts"]) == [0, 40, 80]
        assert list(f["episode_seeds"]) == [3, 4, 5]
        assert np.nonzero(f["timeouts"][:])[0].tolist() == [39, 79, 99]
        assert not f["terminals"][:].any()
        actions = f["actions"][:]
        assert (np.abs(actions) <= 1).all() and actions.std() > 0.5
        # The task one-hots: Box, IIWA, None, Push at the reference's positions.
        hot = np.nonzero(f["observations"][0, 45:61])[0].tolist()
        assert hot == [0, 4, 8, 13]
        attrs = dict(f.attrs)
        assert attrs["task"] == TASK and attrs["dataset_type"] == "random"
        assert attrs["horizon"] == HORIZON and attrs["transitions"] == 100
        assert attrs["creation_command"] == "test" and attrs["suite_version"] == "0.1.0"
        assert len(attrs["suite_commit"]) >= 40
        assert json.loads(attrs["policy_settings"])["actions"].startswith("uniform")
        # Uncompressed and contiguous: memory-mappable.
        assert f["observations"].chunks is None and f["observations"].compression is None


def test_rows_are_what_the_gymnasium_env_gives_for_the_stored_seeds_and_actions(generated):
    root, paths = generated
    data = datasets.open_task(paths[1])
    env = gymnasium.make("composuite_ros/CompoSuiteNative-v0", task=str(data.task.task),
                         horizon=HORIZON)
    for number, (a, b, seed) in enumerate(data.episodes()):
        observation, _ = env.reset(seed=seed)
        for row in range(a, b):
            assert np.array_equal(observation.astype(np.float32).view(np.uint32),
                                  data["observations"][row].view(np.uint32)), row
            observation, reward, terminated, truncated, info = env.step(data["actions"][row])
            assert np.float32(reward) == data["rewards"][row], row
            assert (terminated, truncated or row == b - 1) == \
                (bool(data["terminals"][row]), bool(data["timeouts"][row])), row
            assert bool(info["success"]) == bool(data["successes"][row])
        assert np.array_equal(observation.astype(np.float32),
                              data["episode_final_observations"][number])


def authors_style_get_datasets(root, dataset_type, folders, rows=1_000_000):
    """What the offline repo's `get_datasets` does (its behaviour, not its code): preallocate
    `rows` per task, copy each key in, clear timeouts where terminals are set."""
    n = rows * len(folders)
    out = {"observations": np.empty((n, 93), np.float32), "actions": np.empty((n, 8), np.float32),
           "rewards": np.empty(n, np.float32), "terminals": np.empty(n, np.uint8),
           "timeouts": np.empty(n, np.uint8)}
    for i, folder in enumerate(folders):
        with h5py.File(os.path.join(root, dataset_type, folder, "data.hdf5"), "r") as f:
            for key in out:
                assert key in f, key
                out[key][i * rows:(i + 1) * rows] = f[key][()]
    out["timeouts"][out["terminals"] == 1] = 0
    return out


def test_a_million_row_file_reads_as_the_authors_loader_reads_it(generated, tmp_path):
    """A 1,000,000-row file written by the same writer (the generated episodes tiled: the
    format at full size, without simulating a million steps here)."""
    root, paths = generated
    source = datasets.open_task(paths[0])
    chunk = {k: np.asarray(source[k]) for k in ("observations", "actions", "rewards",
                                                  "terminals", "timeouts", "successes")}
    chunk["terminals"] = chunk["terminals"].copy()
    chunk["terminals"][10] = 1  # a terminal whose timeout must be cleared
    chunk["timeouts"] = chunk["timeouts"].copy()
    chunk["timeouts"][10] = 1
    starts = np.array([0, 40, 80])
    finals = np.asarray(source["episode_final_observations"])
    with DatasetWriter(tmp_path / "random" / FOLDER, 1_000_000, {"task": TASK}) as writer:
        for _ in range(10_000):
            writer.add({**chunk, "episode_starts": starts, "episode_seeds": [3, 4, 5],
                        "episode_final_observations": finals})
        writer.close()
    got = authors_style_get_datasets(tmp_path, "random", [FOLDER])
    assert got["observations"].shape == (1_000_000, 93)
    assert np.array_equal(got["observations"][999_900:], chunk["observations"])
    assert got["terminals"][500_010] == 1 and got["timeouts"][500_010] == 0
    assert got["timeouts"][500_039] == 1
    # Our reader maps the same file without reading it.
    mapped = datasets.open_task(tmp_path / "random" / FOLDER)
    assert mapped.mapped and isinstance(mapped["observations"], np.memmap)
    assert len(mapped) == 1_000_000 and len(mapped["episode_starts"]) == 30_000


def test_verify_replays_bit_for_bit_and_names_the_first_row_that_differs(generated, tmp_path):
    root, paths = generated
    for path in paths:
        verdict = datasets.verify(path, threads=2)
        assert verdict.ok, verdict.difference
        assert (verdict.rows, verdict.episodes) == (100, 3)
    done = cli("verify", str(paths[0]), "--quiet")
    assert done.returncode == 0 and "bit-identical" in done.stdout, done.stderr
    # One observation value one float32 step off: verify names that row.
    tampered = tmp_path / FOLDER
    tampered.mkdir()
    (tampered / "data.hdf5").write_bytes(paths[0].read_bytes())
    with h5py.File(tampered / "data.hdf5", "r+") as f:
        value = f["observations"][57, 3]
        f["observations"][57, 3] = np.nextafter(value, np.float32(np.inf))
    verdict = datasets.verify(tampered)
    assert not verdict.ok and verdict.difference.startswith("row 57 "), verdict.difference
    assert "episode 1 (seed 4" in verdict.difference and "observations" in verdict.difference
    done = cli("verify", str(tampered), "--quiet")
    assert done.returncode == 1 and "DIFFERENT: row 57" in done.stdout
    # An action changed: the rows after it differ from the simulation.
    with h5py.File(tampered / "data.hdf5", "r+") as f:
        f["observations"][57, 3] = value
        f["actions"][12, 0] = -f["actions"][12, 0]
    assert datasets.verify(tampered).difference.startswith("row 13 ")
    # A success flag that is not rewards == 1.
    with h5py.File(tampered / "data.hdf5", "r+") as f:
        f["successes"][5] = 1
    assert "successes must equal rewards == 1" in datasets.verify(tampered).difference


def test_the_same_file_for_one_thread_and_two(generated, tmp_path):
    root, paths = generated
    again = datasets.generate(tmp_path, datasets.select_tasks([TASK]), ["random"],
                              transitions=100, horizon=HORIZON, first_seed=3, threads=1,
                              command="test")
    with h5py.File(paths[0]) as a, h5py.File(again[0]) as b:
        for key in a:
            assert np.array_equal(a[key][()], b[key][()]), key


def test_many_tasks_read_lazily_as_one_dataset(generated):
    root, _ = generated
    data = datasets.load(root, "random")
    assert len(data) == 200 and [t.folder for t in data.tasks] == [
        FOLDER, "Kinova3_Plate_ObjectWall_Shelf"]
    assert all(p.mapped for p in data.parts)
    rows = data.rows(np.array([150, 3, 99, 100]))
    assert np.array_equal(rows["observations"][1], data.parts[0]["observations"][3])
    assert np.array_equal(rows["observations"][0], data.parts[1]["observations"][50])
    assert np.array_equal(rows["actions"][3], data.parts[1]["actions"][0])
    batch = data.sample(64, np.random.default_rng(0))
    assert batch["observations"].shape == (64, 93) and batch["terminals"].dtype == np.uint8
    assert sum(len(c["rewards"]) for _, c in data.chunks(rows=30)) == 200
    same = datasets.load(root, "random", tasks=["IIWA/Box/None/Push"])
    assert len(same) == 100


def test_gzip_files_read_and_verify_too(tmp_path):
    paths = datasets.generate(tmp_path, datasets.select_tasks([TASK]), ["random"],
                              transitions=50, horizon=HORIZON, compression="gzip", command="t")
    data = datasets.open_task(paths[0])
    assert not data.mapped and data.attrs["compression"] == "gzip"
    assert datasets.verify(paths[0]).ok
    loaded = datasets.load(tmp_path, "random")
    assert loaded.rows(np.array([49, 0, 49]))["rewards"].shape == (3,)


def test_minari_round_trip_recovers_the_environment(generated, tmp_path, monkeypatch):
    minari = pytest.importorskip("minari")
    monkeypatch.setenv("MINARI_DATASETS_PATH", str(tmp_path))
    from composuite_ros.datasets.minari_export import to_minari
    root, paths = generated
    dataset_id = to_minari(paths[0])
    assert dataset_id == "composuite/iiwa-box-none-push/random-v0"
    dataset = minari.load_dataset(dataset_id)
    assert dataset.total_episodes == 3 and dataset.total_steps == 100
    data = datasets.open_task(paths[0])
    episodes = list(dataset.iterate_episodes())
    for episode, (a, b, seed) in zip(episodes, data.episodes()):
        assert episode.observations.shape == (b - a + 1, 93)
        assert np.array_equal(episode.observations[:-1].astype(np.float32),
                              data["observations"][a:b])
        assert np.array_equal(episode.actions, data["actions"][a:b])
        assert list(episode.truncations) == [bool(t) for t in data["timeouts"][a:b]]
    env = dataset.recover_environment()
    assert env.unwrapped.task == composuite_ros.Task.parse(TASK)
    observation, _ = env.reset(seed=int(data["episode_seeds"][0]))
    assert np.array_equal(observation.astype(np.float32),
                          episodes[0].observations[0].astype(np.float32))
    # The CLI's --format minari writes it too.
    done = cli("generate", "--out", str(tmp_path / "out"), "--tasks", TASK, "--transitions",
               "45", "--horizon", "40", "--format", "minari", "--quiet",
               env={**os.environ, "MINARI_DATASETS_PATH": str(tmp_path / "m")})
    assert done.returncode == 0, done.stderr
    assert "minari: composuite/iiwa-box-none-push/random-v0" in done.stdout


def test_an_interrupted_run_leaves_no_data_file_and_resume_finishes_it(tmp_path):
    tasks = datasets.select_tasks([TASK, "Jaco/box/no_obstacle/push"])

    def interrupt(line):
        if "Jaco" in line:
            raise KeyboardInterrupt

    with pytest.raises(KeyboardInterrupt):
        datasets.generate(tmp_path, tasks, ["random"], transitions=80, horizon=HORIZON,
                          progress=interrupt, command="t")
    jaco = tmp_path / "random" / "Jaco_Box_None_Push"
    assert (tmp_path / "random" / FOLDER / "data.hdf5").exists()
    assert list(jaco.iterdir()) == []
    with pytest.raises(DatasetError, match="already holds files.*--overwrite.*--resume"):
        datasets.generate(tmp_path, tasks, ["random"], transitions=80, horizon=HORIZON)
    before = (tmp_path / "random" / FOLDER / "data.hdf5").stat().st_mtime_ns
    written = datasets.generate(tmp_path, tasks, ["random"], transitions=80, horizon=HORIZON,
                                resume=True, command="t")
    assert written == [jaco / "data.hdf5"]
    assert (tmp_path / "random" / FOLDER / "data.hdf5").stat().st_mtime_ns == before
    assert datasets.verify(jaco).ok


def test_tasks_by_name_filter_and_split_file(tmp_path):
    assert len(datasets.select_tasks()) == 256
    picked = datasets.select_tasks(robot=["Kinova3"], objective=["push", "Shelf"])
    assert len(picked) == 32 and {t.task.robot for t in picked} == {"Gen3"}
    split = tmp_path / "split_0.json"
    split.write_text(json.dumps({"train": [["IIWA", "Hollowbox", "GoalWall", "Trashcan"],
                                           ["Kinova3", "Box", "None", "PickPlace"]],
                                 "test": [["Panda", "Dumbbell", "ObjectDoor", "Shelf"]]}))
    assert [t.folder for t in datasets.select_tasks(split=split)] == [
        "IIWA_Hollowbox_GoalWall_Trashcan", "Kinova3_Box_None_PickPlace"]
    assert [str(t.task) for t in datasets.select_tasks(split=split, split_part="test")] == [
        "Panda/dumbbell/object_door/shelf"]
    assert [t.folder for t in datasets.select_tasks(split=split, robot=["IIWA"])] == [
        "IIWA_Hollowbox_GoalWall_Trashcan"]


@pytest.mark.parametrize("args, message", [
    (["--tasks", "IIWA/box/no_obstacle/juggle"],
     "unknown objective 'juggle'; valid: pick_place, push, trash_can, shelf (or the reference's "
     "PickPlace, Push, Trashcan, Shelf)"),
    (["--tasks", "IIWA/box/pick_place"], "is not robot/object/obstacle/objective"),
    (["--types", "expertise"], "dataset type 'expertise' is unknown; valid: expert, medium"),
    (["--types", "medium-replay"], "cannot generate 'medium-replay' data: medium-replay is "
                                   "what a learner saw"),
    (["--types", "medium", "--target-success", "1.5"], "must lie strictly between 0 and 1"),
    (["--types", "medium", "--medium-table", "/nonexistent/table.json"],
     "medium noise table /nonexistent/table.json does not exist"),
    (["--robot", "UR5"], "unknown robot 'UR5'; valid: IIWA, Jaco, Gen3, Panda"),
    (["--transitions", "0"], "must be positive"),
    (["--transitions", "-5"], "must be positive"),
    (["--format", "parquet"], "invalid choice: 'parquet'"),
    (["--compression", "lz4"], "invalid choice: 'lz4'"),
    (["--seed", "4294967296"], "outside the reference's 0..4294967295"),
])
def test_bad_input_is_refused_naming_what_is_valid(tmp_path, args, message):
    done = cli("generate", "--out", str(tmp_path / "d"), "--tasks", TASK, *args)
    assert done.returncode == 2, done
    assert message in done.stderr, done.stderr
    assert not (tmp_path / "d").exists()


def test_bad_split_files_and_paths_are_refused(tmp_path):
    bad = tmp_path / "split.json"
    bad.write_text(json.dumps({"train": [["IIWA", "box", "None", "PickPlace"]]}))
    done = cli("generate", "--out", str(tmp_path / "d"), "--split", str(bad))
    assert done.returncode == 2
    assert "object 'box' is not in the reference's spellings; valid: Box, Hollowbox, Plate, " \
           "Dumbbell" in done.stderr
    done = cli("generate", "--out", str(tmp_path / "d"), "--split", str(tmp_path / "nope.json"))
    assert done.returncode == 2 and "does not exist" in done.stderr
    done = cli("verify", str(tmp_path / "missing"))
    assert done.returncode == 2 and "does not exist" in done.stderr
    (tmp_path / "not.hdf5").write_text("hello")
    done = cli("verify", str(tmp_path / "not.hdf5"))
    assert done.returncode == 2 and "is not an HDF5 file" in done.stderr


def test_medium_replay_from_a_ppo_run_replays_bit_for_bit(tmp_path):
    """The PPO learner records what it played (--dataset-out); `subsample` draws whole episodes
    of it into a medium-replay file that `verify` re-simulates from the seeds and actions."""
    script = os.path.join(os.path.dirname(__file__), "..", "..", "examples", "ppo_train.py")
    run = tmp_path / "run.hdf5"
    done = subprocess.run([sys.executable, script, "--task", TASK, "--num-envs", "2",
                           "--epochs", "2", "--steps-per-epoch", "1100", "--pi-iters", "2",
                           "--v-iters", "2", "--dataset-out", str(run)],
                          capture_output=True, text=True)
    assert done.returncode == 0, done.stderr
    assert "run file" in done.stdout and "4 episodes, 2000 rows" in done.stdout, done.stdout
    with h5py.File(run) as f:
        assert list(f["episode_starts"]) == [0, 500, 1000, 1500]
        seeds = list(f["episode_seeds"])
        assert seeds[:2] == [42, 43]          # vector reset(seed=42): env i gets 42 + i
        assert f.attrs["task"] == TASK and "ppo_train.py" in f.attrs["learner"]
    done = cli("subsample", str(run), "--out", str(tmp_path / "d"), "--transitions", "1200",
               "--seed", "1")
    assert done.returncode == 0, done.stderr
    data = datasets.open_task(tmp_path / "d" / "medium-replay" / FOLDER)
    assert len(data) == 1200 and data.attrs["dataset_type"] == "medium-replay"
    assert len(data.episodes()) == 3 and data["timeouts"][1199] == 1
    assert set(int(s) for s in data["episode_seeds"]) <= set(int(s) for s in seeds)
    verdict = datasets.verify(data.path)
    assert verdict.ok, verdict.difference
    done = cli("subsample", str(run), "--out", str(tmp_path / "d"), "--transitions", "5000")
    assert done.returncode == 2 and "holds 2,000 rows in 4 episodes; 5,000" in done.stderr
