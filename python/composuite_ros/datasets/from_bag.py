"""A recorded session (a rosbag2 bag of MCAP files, `composuite session` / `composuite launch
--record`) as offline datasets: every lockstep episode whose agent acted in the reference's
action space (`reference_action_stamped` or `reference_action`), one file per task, its rows
played again in-process from the recorded seeds and actions — and each replayed observation
checked against the one the sim published, so a file is only written when the bag and this
version of the suite agree.

Commands carry no episode number; a command belongs to the episode whose step-0 observation was
the last one published before it (publish times), as `composuite bag replay` assigns them. A
stamped action stamped before its episode began is dropped, as the sim drops it.
"""

from __future__ import annotations

import bisect
import os
from collections import defaultdict
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from .. import _native
from .generate import FORMAT, default_threads, suite_provenance
from .layout import DatasetError, TaskNames, names_of, task_file
from .writer import DatasetWriter

OBSERVATION = "composuite_msgs/msg/Observation"
SCENE = "composuite_msgs/msg/Scene"
STAMPED = "composuite_msgs/msg/ReferenceAction"
UNSTAMPED = "std_msgs/msg/Float64MultiArray"
JOINT_STATE = "sensor_msgs/msg/JointState"


def _namespace(topic: str) -> str:
    ns, _, _ = topic.rpartition("/")
    return ns or "/"


def _stamp(header) -> int:
    return int(header.stamp.sec) * 1_000_000_000 + int(header.stamp.nanosec)


@dataclass
class Episode:
    namespace: str
    number: int
    task: TaskNames
    seed: int
    horizon: int
    start_stamp: int
    observations: dict = field(default_factory=dict)  # step -> (publish time, flat)
    commands: list = field(default_factory=list)      # (publish time, kind, values, stamp)


def read_episodes(bag: str | os.PathLike) -> list[Episode]:
    """The bag's episodes with their recorded observations and the commands sent in them."""
    try:
        from mcap.reader import make_reader
        from mcap_ros2.decoder import DecoderFactory
    except ImportError:
        raise DatasetError("from-bag needs the mcap readers: pip install "
                           "'composuite_ros[from-bag]'") from None
    bag = Path(bag)
    files = sorted(bag.glob("*.mcap")) if bag.is_dir() else [bag]
    if not files or not all(f.exists() for f in files):
        raise DatasetError(f"{bag} holds no .mcap file: give a bag folder (with metadata.yaml "
                           "and *.mcap), as `composuite session` writes under bag/")
    episodes: dict[tuple[str, int], Episode] = {}
    observations = []
    commands: dict[str, list] = defaultdict(list)
    for path in files:
        with open(path, "rb") as f:
            reader = make_reader(f, decoder_factories=[DecoderFactory()])
            for schema, channel, message, decoded in reader.iter_decoded_messages():
                ns, kind = _namespace(channel.topic), schema.name
                leaf = channel.topic.rsplit("/", 1)[-1]
                if kind == SCENE:
                    t = decoded.task
                    key = (ns, int(decoded.episode))
                    if key not in episodes and decoded.episode > 0:
                        episodes[key] = Episode(
                            ns, int(decoded.episode),
                            names_of([t.robot, t.object, t.obstacle, t.objective]),
                            int(decoded.seed), int(decoded.horizon), _stamp(decoded.header))
                elif kind == OBSERVATION:
                    observations.append(((ns, int(decoded.episode)), int(decoded.step),
                                         message.publish_time, np.asarray(decoded.flat)))
                elif kind == STAMPED and leaf == "reference_action_stamped":
                    commands[ns].append((message.publish_time, "reference", decoded.action,
                                         _stamp(decoded.header)))
                elif kind == UNSTAMPED and leaf == "reference_action":
                    commands[ns].append((message.publish_time, "reference", decoded.data, 0))
                elif kind == JOINT_STATE and leaf == "joint_command":
                    commands[ns].append((message.publish_time, "joint_command", None, 0))
    for key, step, time, flat in observations:
        if key in episodes:
            episodes[key].observations[step] = (time, flat)
    # Only episodes whose start was recorded can be played again.
    episodes = {k: e for k, e in episodes.items() if 0 in e.observations}
    for ns, sent in commands.items():
        starts = sorted((e.observations[0][0], e.number) for e in episodes.values()
                        if e.namespace == ns)
        times = [start for start, _ in starts]
        for command in sorted(sent, key=lambda c: c[0]):
            # The last episode whose step-0 observation was published before the command.
            owner = bisect.bisect_left(times, command[0]) - 1
            if owner >= 0:
                episodes[(ns, starts[owner][1])].commands.append(command)
    return [episodes[k] for k in sorted(episodes)]


def _actions(episode: Episode) -> np.ndarray:
    """The episode's actions as the float32 rows a dataset stores; refused where the session
    did not act in the reference's action space."""
    where = f"{episode.namespace} episode {episode.number} ({episode.task.task}, seed {episode.seed})"
    if any(kind == "joint_command" for _, kind, _, _ in episode.commands):
        raise DatasetError(
            f"{where} was driven by joint_command (absolute joint targets), not in the "
            "reference's action space: a dataset stores the reference's 8 numbers "
            "(reference_action_stamped / reference_action), so this session cannot become one; "
            "`composuite session --policy planned` records the planned expert in that space")
    rows = [values for _, _, values, stamp in episode.commands
            if stamp == 0 or stamp >= episode.start_stamp]
    rows = rows[:episode.horizon]
    actions = np.asarray(rows, dtype=np.float64).reshape(-1, 8)
    if not np.isfinite(actions).all() or (np.abs(actions) > 1).any():
        raise DatasetError(f"{where}: an action lies outside the reference's [-1, 1]^8")
    stored = actions.astype(np.float32)
    if not np.array_equal(stored.astype(np.float64), actions):
        raise DatasetError(f"{where}: actions that are not float32 values were sent; a dataset "
                           "stores float32, which would not replay this episode")
    return stored


def from_bag(bag: str | os.PathLike, root: str | os.PathLike, *, dataset_type: str = "from-bag",
             threads: int | None = None, overwrite: bool = False, command: str = "") -> list[Path]:
    """Write the bag's episodes under `root/{dataset_type}/{task}/data.hdf5` (one file per
    task, episodes in namespace and episode order); returns the files."""
    episodes = [e for e in read_episodes(bag) if e.commands]
    if not episodes:
        raise DatasetError(f"{bag} holds no lockstep episode with commands (it needs scene, "
                           "observation and the agent's actions)")
    by_task: dict[TaskNames, list[Episode]] = defaultdict(list)
    for e in episodes:
        by_task[e.task].append(e)
    paths = []
    threads = threads or default_threads()
    for task, group in by_task.items():
        path = task_file(root, dataset_type, task)
        if path.exists() and not overwrite:
            raise DatasetError(f"{path} exists; pass --overwrite to replace it")
        horizons = {e.horizon for e in group}
        if len(horizons) != 1:
            raise DatasetError(f"{task.task}: episodes of horizons {sorted(horizons)} in one bag")
        horizon = horizons.pop()
        actions = [_actions(e) for e in group]
        kept = [(e, a) for e, a in zip(group, actions) if len(a)]
        starts = np.cumsum([0] + [len(a) for _, a in kept[:-1]]).astype(np.int64)
        seeds = np.array([e.seed for e, _ in kept], dtype=np.uint64)
        replayed = _native.replay(str(task.task), seeds, starts,
                                  np.concatenate([a for _, a in kept]), threads=threads,
                                  horizon=horizon)
        offsets = np.concatenate([[0], np.cumsum(replayed["lengths"])])
        for k, (e, a) in enumerate(kept):
            where = f"{e.namespace} episode {e.number} ({task.task}, seed {e.seed})"
            if replayed["lengths"][k] != len(a):
                raise DatasetError(f"{where}: the simulation ended it after "
                                   f"{replayed['lengths'][k]} steps, but {len(a)} actions were "
                                   "sent in it")
            for step, (_, flat) in e.observations.items():
                if step <= len(a):
                    again = (replayed["observations"][offsets[k] + step] if step < len(a)
                             else replayed["episode_final_observations"][k])
                    if not np.array_equal(again, flat.astype(np.float32)):
                        raise DatasetError(
                            f"{where}, step {step}: the replayed observation differs from the "
                            "recorded one (was the bag made by another version of the suite?)")
        rows = int(offsets[-1])
        attrs = {"format": FORMAT, **suite_provenance(), "task": str(task.task),
                 "task_reference": task.folder, "dataset_type": dataset_type,
                 "policy": "a recorded session's agent", "policy_settings": {"bag": str(bag)},
                 "horizon": horizon, "transitions": rows, "compression": "none",
                 "creation_command": command}
        with DatasetWriter(path.parent, rows, attrs) as writer:
            writer.add({**{k: replayed[k] for k in ("observations", "actions", "rewards",
                                                     "terminals", "timeouts", "successes")},
                        "episode_starts": starts, "episode_seeds": seeds,
                        "episode_final_observations": replayed["episode_final_observations"]})
            paths.append(writer.close())
    return paths
