"""CompoSuite's offline-RL datasets, written by the suite (`composuite-dataset` is the command).

Files follow the offline benchmark's layout, which the authors' loader reads unchanged:
`{root}/{type}/{Robot}_{Object}_{Obstacle}_{Objective}/data.hdf5` with `observations` (N, 93)
float32, `actions` (N, 8) float32 in the reference's action space, `rewards`, `terminals`,
`timeouts`, `successes` (N,), plus each episode's seed, first row and final observation, so
every row can be re-simulated (`verify`).

    from composuite_ros import datasets
    tasks = datasets.select_tasks(["IIWA/box/no_obstacle/pick_place"])
    datasets.generate("data", tasks, ["expert", "medium", "random"], transitions=100_000)
    data = datasets.load("data", "random")          # memory-mapped, not copied
    batch = data.sample(256)                         # {"observations": (256, 93), ...}
    assert datasets.verify("data/random/IIWA_Box_None_PickPlace").ok

Needs h5py (`pip install 'composuite_ros[datasets]'`); Minari and d3rlpy are extras too.
"""

from . import medium
from .generate import DEFAULT_TRANSITIONS, Shard, generate, plan, suite_provenance, write_shard
from .layout import (DATASET_TYPES, GENERATED_TYPES, REFERENCE_SPELLINGS, TASKS, DatasetError,
                     TaskNames, names_of, read_split, select_tasks, task_file)
from .reader import OfflineDataset, TaskData, load, open_task, to_d3rlpy
from .verify import Verdict, verify
from .writer import DatasetWriter

__all__ = ["DATASET_TYPES", "DEFAULT_TRANSITIONS", "GENERATED_TYPES", "REFERENCE_SPELLINGS",
           "TASKS", "DatasetError", "DatasetWriter", "OfflineDataset", "Shard", "TaskData",
           "TaskNames", "Verdict", "generate", "load", "medium", "names_of", "open_task", "plan",
           "read_split", "select_tasks", "suite_provenance", "task_file", "to_d3rlpy", "verify",
           "write_shard"]
