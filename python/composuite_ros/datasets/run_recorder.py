"""What a learner saw, kept for `medium-replay`: every episode a Gymnasium vector env of the
in-process suite plays (a run file), and a medium-replay dataset subsampled from it.

A run file is an HDF5 file with the dataset keys growing episode by episode (in the order
episodes end). `subsample` picks whole episodes from it at random (seeded) until the dataset's
row count is reached, keeps them in the run's order, and cuts the last one at the final row as
a timeout, as `generate` does — so a medium-replay file re-simulates with `verify` like any other.

    recorder = RunRecorder("run.hdf5", env)       # env: CompoSuiteNativeVectorEnv, one task
    obs, infos = env.reset(seed=0); recorder.reset(obs, infos)
    ... obs, rew, term, trunc, infos = env.step(actions); recorder.step(actions, obs, rew, term, trunc, infos)
    recorder.close()
    subsample("run.hdf5", "data", transitions=1_000_000)
"""

from __future__ import annotations

import os
from pathlib import Path
from typing import Any, Mapping

import numpy as np

from .generate import FORMAT, suite_provenance
from .layout import DatasetError, names_of, task_file
from .writer import ACTION_SIZE, OBSERVATION_SIZE, ROW_KEYS, DatasetWriter, _h5py

EPISODE_KEYS = {"episode_starts": (np.int64, ()), "episode_seeds": (np.uint64, ()),
                "episode_final_observations": (np.float32, (OBSERVATION_SIZE,))}


class _Episode:
    def __init__(self, seed: int, observation: np.ndarray):
        self.seed = seed
        self.observation = observation.astype(np.float32)
        self.rows: dict[str, list] = {k: [] for k in ROW_KEYS}

    def add(self, action, reward, terminal, timeout, success, next_observation) -> None:
        self.rows["observations"].append(self.observation)
        self.rows["actions"].append(np.asarray(action, dtype=np.float32))
        self.rows["rewards"].append(np.float32(reward))
        self.rows["terminals"].append(np.uint8(terminal))
        self.rows["timeouts"].append(np.uint8(timeout))
        self.rows["successes"].append(np.uint8(success))
        self.observation = next_observation.astype(np.float32)


class RunRecorder:
    """Records the episodes of a one-task in-process vector env (`CompoSuiteNativeVectorEnv`,
    Gymnasium's next-step autoreset) into the run file at `path`. Feed it every `reset` and
    `step` of the env, with the float32 actions the env was stepped with."""

    def __init__(self, path: str | os.PathLike, env, attrs: Mapping[str, Any] = ()):
        tasks = {str(t) for t in env.tasks}
        if len(tasks) != 1:
            raise DatasetError(f"a run file holds one task; the env has {sorted(tasks)}")
        if env.single_observation_space.shape != (OBSERVATION_SIZE,):
            raise DatasetError("a run file needs the 93-value observation (use_task_id_obs=True)")
        self.task = names_of(tasks.pop())
        self.num_envs = env.num_envs
        self.path = Path(path)
        self.episodes = 0
        self.rows = 0
        self._open: list[_Episode | None] = [None] * self.num_envs
        h5py = _h5py()
        self._file = h5py.File(self.path, "w")
        for key, (dtype, shape) in {**ROW_KEYS, **EPISODE_KEYS}.items():
            self._file.create_dataset(key, shape=(0, *shape), maxshape=(None, *shape),
                                      dtype=dtype, chunks=(4096, *shape))
        horizon = int(env.horizon) if hasattr(env, "horizon") else 500
        for key, value in {**suite_provenance(), "task": str(self.task.task),
                           "horizon": horizon, "kind": "composuite-ros run file",
                           **dict(attrs)}.items():
            self._file.attrs[key] = value

    def reset(self, observations: np.ndarray, infos: Mapping[str, Any]) -> None:
        """After `env.reset(...)`: every environment starts an episode."""
        for i in range(self.num_envs):
            self._open[i] = _Episode(int(infos["seed"][i]), np.asarray(observations[i]))

    def step(self, actions, observations, rewards, terminations, truncations,
             infos: Mapping[str, Any]) -> None:
        """After `env.step(actions)`: rows for the environments that stepped, a new episode for
        those that autoreset."""
        actions = np.asarray(actions)
        if actions.dtype != np.float32 or actions.shape != (self.num_envs, ACTION_SIZE):
            raise DatasetError(f"record the float32 ({self.num_envs}, 8) actions the env was "
                               f"stepped with; got {actions.dtype} {actions.shape}")
        resets = np.asarray(infos.get("_seed", np.zeros(self.num_envs, bool)))
        success = np.asarray(infos.get("success", np.zeros(self.num_envs, bool)))
        for i in range(self.num_envs):
            if resets[i]:
                self._open[i] = _Episode(int(infos["seed"][i]), np.asarray(observations[i]))
                continue
            episode = self._open[i]
            if episode is None:
                raise DatasetError(f"environment {i} stepped without a recorded reset")
            episode.add(actions[i], rewards[i], terminations[i], truncations[i], success[i],
                        np.asarray(observations[i]))
            if terminations[i] or truncations[i]:
                self._write(episode)
                self._open[i] = None

    def _write(self, episode: _Episode) -> None:
        n = len(episode.rows["rewards"])
        columns = {k: np.asarray(v) for k, v in episode.rows.items()}
        columns["episode_starts"] = np.array([self.rows])
        columns["episode_seeds"] = np.array([episode.seed], dtype=np.uint64)
        columns["episode_final_observations"] = episode.observation[None]
        for key, values in columns.items():
            data = self._file[key]
            at = len(data)
            data.resize(at + len(values), axis=0)
            data[at:] = values
        self.rows += n
        self.episodes += 1

    def close(self) -> None:
        """Finish the file (episodes still running are left out)."""
        self._file.attrs["episodes"] = self.episodes
        self._file.close()


def subsample(run: str | os.PathLike, root: str | os.PathLike, transitions: int, *,
              seed: int = 0, dataset_type: str = "medium-replay", overwrite: bool = False,
              command: str = "") -> Path:
    """A `dataset_type` file of `transitions` rows under `root`, from whole episodes of the run
    file drawn at random (`seed`), kept in the run's order; the last cut at the final row."""
    h5py = _h5py()
    if transitions <= 0:
        raise DatasetError(f"transitions must be positive; got {transitions}")
    with h5py.File(run, "r") as f:
        if f.attrs.get("kind") != "composuite-ros run file":
            raise DatasetError(f"{run} is not a run file (RunRecorder writes them)")
        task = names_of(str(f.attrs["task"]))
        starts = f["episode_starts"][()]
        ends = np.append(starts[1:], len(f["rewards"]))
        total = int(ends[-1] - starts[0]) if len(starts) else 0
        if total < transitions:
            raise DatasetError(f"{run} holds {total:,} rows in {len(starts):,} episodes; "
                               f"{transitions:,} were asked for")
        order = np.random.default_rng(seed).permutation(len(starts))
        lengths = (ends - starts)[order]
        needed = int(np.searchsorted(np.cumsum(lengths), transitions)) + 1
        chosen = np.sort(order[:needed])
        path = task_file(root, dataset_type, task)
        if path.exists() and not overwrite:
            raise DatasetError(f"{path} exists; pass --overwrite to replace it")
        attrs = {k: (v.decode() if isinstance(v, bytes) else v) for k, v in f.attrs.items()
                 if k not in ("kind", "episodes")}
        attrs.update({"format": FORMAT, "dataset_type": dataset_type,
                      "transitions": transitions, "subsample_seed": seed,
                      "subsampled_from": f"{Path(run).name}: {total:,} rows, "
                                         f"{len(starts):,} episodes",
                      "compression": "none", "creation_command": command,
                      **{f"learner_{k}": v for k, v in attrs.items()
                         if k in ("suite_version", "suite_commit")},
                      **suite_provenance()})
        with DatasetWriter(path.parent, transitions, attrs) as writer:
            for index in chosen:
                a, b = int(starts[index]), int(ends[index])
                b = min(b, a + transitions - writer.written)
                chunk = {k: f[k][a:b] for k in ROW_KEYS}
                if b < ends[index]:  # cut: the last row becomes a timeout
                    chunk["timeouts"] = chunk["timeouts"].copy()
                    chunk["timeouts"][-1] = 1
                    final = f["observations"][b][None]
                else:
                    final = f["episode_final_observations"][index][None]
                chunk.update(episode_starts=[0], episode_seeds=f["episode_seeds"][index:index + 1],
                             episode_final_observations=final)
                writer.add(chunk)
            return writer.close()
