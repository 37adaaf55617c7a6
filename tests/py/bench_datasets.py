"""Offline datasets' figures (nothing is asserted): transitions/s written per type (random,
expert, medium) on one thread and on every core (write included), and reading 8 tasks — our memory-mapped `load`
beside a loader that does what the authors' `get_datasets` does (preallocate, copy every key of
every file into RAM) — in rows/s and peak RSS, each reader in a fresh process.

    python tests/py/bench_datasets.py --rows 20000 --read-rows 100000 --json
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

from composuite_ros import datasets
from composuite_ros.datasets import medium

# The reference's four tasks of its speed protocol, then four more for the 8-task read.
TASKS = ["IIWA/box/no_obstacle/pick_place", "Jaco/plate/object_wall/shelf",
         "Gen3/dumbbell/goal_wall/trash_can", "Panda/hollow_box/object_door/push",
         "IIWA/plate/goal_wall/push", "Jaco/hollow_box/no_obstacle/trash_can",
         "Gen3/box/object_door/shelf", "Panda/dumbbell/object_wall/pick_place"]

READER = r'''
import resource, sys, time, json
import numpy as np, h5py
root, mode, folders = sys.argv[1], sys.argv[2], sys.argv[3:]
started = time.perf_counter()
if mode == "authors":
    rows = [h5py.File(f"{root}/random/{f}/data.hdf5", "r")["rewards"].shape[0] for f in folders]
    n = sum(rows)
    out = {"observations": np.empty((n, 93), np.float32), "actions": np.empty((n, 8), np.float32),
           "rewards": np.empty(n, np.float32), "terminals": np.empty(n, np.uint8),
           "timeouts": np.empty(n, np.uint8)}
    at = 0
    for f, r in zip(folders, rows):
        with h5py.File(f"{root}/random/{f}/data.hdf5", "r") as h:
            for key in out:
                out[key][at:at + r] = h[key][()]
        at += r
    out["timeouts"][out["terminals"] == 1] = 0
    checksum = float(out["observations"][:, :3].sum())
else:
    from composuite_ros import datasets
    data = datasets.load(root, "random", tasks=folders)
    n = len(data)
    if mode == "ours-pass":
        checksum = 0.0
        for _, chunk in data.chunks(rows=65536):
            checksum += float(chunk["observations"][:, :3].sum())
    else:  # ours-sample: as many rows as the dataset holds, in batches of 256 drawn uniformly
        rng = np.random.default_rng(0)
        checksum = 0.0
        for _ in range(n // 256):
            checksum += float(data.sample(256, rng)["observations"][:, :3].sum())
elapsed = time.perf_counter() - started
# Resident memory of this process's own data (anonymous pages) at the end, beside the peak RSS,
# which also counts the file pages a memory map has touched (page cache, given back on demand).
anon = next(int(line.split()[1]) for line in open("/proc/self/status") if line.startswith("RssAnon"))
print(json.dumps({"rows": n, "seconds": elapsed,
                  "peak_rss_mb": resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024,
                  "anon_mb": anon / 1024}))
'''


def generation(rows: int, threads: int, dataset_type: str) -> dict:
    """Transitions/s writing `dataset_type` for the first four tasks (medium: those the shipped
    noise table holds, so no calibration is timed)."""
    out = {}
    calibrated = medium.NoiseTable.load(medium.TABLE).tasks
    with tempfile.TemporaryDirectory() as root:
        for i, task in enumerate(TASKS[:4]):
            if dataset_type == "medium" and task not in calibrated:
                continue
            started = time.perf_counter()
            datasets.generate(Path(root) / str(i), datasets.select_tasks([task]),
                              [dataset_type], transitions=rows, threads=threads,
                              command="bench")
            out[task] = rows / (time.perf_counter() - started)
    return out


def reading(read_rows: int, root: Path) -> dict:
    tasks = datasets.select_tasks(TASKS)
    if not (root / "random").exists():
        print(f"generating 8 x {read_rows:,} rows into {root} ...", file=sys.stderr)
        datasets.generate(root, tasks, ["random"], transitions=read_rows, command="bench")
    folders = [t.folder for t in tasks]
    out = {}
    for mode in ("authors", "ours-pass", "ours-sample"):
        done = subprocess.run([sys.executable, "-c", READER, str(root), mode, *folders],
                              capture_output=True, text=True, check=True)
        result = json.loads(done.stdout)
        result["rows_per_s"] = result["rows"] / result["seconds"]
        out[mode] = result
    return out


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--rows", type=int, default=20_000, help="rows per task generated")
    parser.add_argument("--read-rows", type=int, default=100_000, help="rows per task read")
    parser.add_argument("--read-root", type=Path, help="keep the 8 read files here (reused)")
    parser.add_argument("--threads", type=int, default=len(os.sched_getaffinity(0)))
    parser.add_argument("--types", nargs="+", default=["random", "expert", "medium"],
                        help="types whose writing is timed (default random expert medium)")
    parser.add_argument("--read-only", action="store_true", help="only the read figures")
    parser.add_argument("--json", action="store_true")
    args = parser.parse_args()
    figures = {}
    if not args.read_only:
        for t in args.types:
            figures[f"{t}_one_thread"] = generation(args.rows, 1, t)
            figures[f"{t}_{args.threads}_threads"] = generation(args.rows, args.threads, t)
    if args.read_root:
        figures["read"] = reading(args.read_rows, args.read_root)
    else:
        with tempfile.TemporaryDirectory() as root:
            figures["read"] = reading(args.read_rows, Path(root))
    for name in [k for k in figures if k != "read"]:
        values = figures[name]
        if not values:
            print(f"{name}: no task of the four in the noise table")
            continue
        print(f"{name}: " + ", ".join(f"{t} {v:,.0f}" for t, v in values.items())
              + f" transitions/s (median {np.median(list(values.values())):,.0f})")
    for mode, r in figures["read"].items():
        print(f"read 8 tasks, {mode}: {r['rows']:,} rows, {r['rows_per_s']:,.0f} rows/s, "
              f"peak RSS {r['peak_rss_mb']:,.0f} MB (file pages included), own memory at the "
              f"end {r['anon_mb']:,.0f} MB")
    if args.json:
        print(json.dumps(figures, indent=1))


if __name__ == "__main__":
    main()
