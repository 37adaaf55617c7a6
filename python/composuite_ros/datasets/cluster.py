"""Shards on a Ray cluster: each (task, type) file a Ray task, retried by Ray when its worker
dies. A shard's rows depend only on the shard (its seeds are its own), so a retried shard comes
out bit-identical, and a half-written file of a dead worker is replaced (it was never renamed to
`data.hdf5`). Every node must see the output folder at the same path (one machine, or a shared
file system).

    ray start --head --node-ip-address 127.0.0.1 --port 6379
    composuite-dataset generate --out /shared/data --robot IIWA --ray 127.0.0.1:6379
"""

from __future__ import annotations

import os
import socket
from pathlib import Path
from typing import Callable, Sequence

from .generate import Shard, write_shard
from .layout import DatasetError

# Times Ray runs a shard again after its worker died.
MAX_RETRIES = 3


def _shard_task(shard: Shard, root: str, threads: int) -> str:
    """A Ray worker's job: one shard, written whole (its process title is `ray::_shard_task`)."""
    return str(write_shard(shard, root, threads=threads))


def _check_answers(address: str, timeout: float = 5.0) -> None:
    """Refuse an address nothing listens on, before Ray waits for it (it would retry for a
    minute)."""
    if address == "auto":
        return
    host, _, port = address.removeprefix("ray://").rpartition(":")
    try:
        with socket.create_connection((host or "127.0.0.1", int(port)), timeout=timeout):
            pass
    except (OSError, ValueError) as e:
        raise DatasetError(
            f"the Ray address {address!r} does not answer ({e}); give the head node's "
            "HOST:PORT as `ray start --head` printed it (e.g. 127.0.0.1:6379), or 'auto' for "
            "the cluster this machine is part of") from None


def generate_on_ray(address: str, root: str | os.PathLike, shards: Sequence[Shard], *,
                    threads: int = 1, progress: Callable[[str], None] | None = None
                    ) -> list[Path]:
    """Write `shards` as Ray tasks of `threads` CPUs each on the cluster at `address`; returns
    the files in the shards' order."""
    try:
        import ray
    except ImportError:
        raise DatasetError("--ray needs Ray: pip install 'composuite_ros[ray]'") from None
    _check_answers(address)
    try:
        ray.init(address=address, logging_level="ERROR", log_to_driver=False)
    except (ConnectionError, RuntimeError, ValueError) as e:
        raise DatasetError(f"could not join the Ray cluster at {address!r}: {e}") from None
    try:
        task = ray.remote(max_retries=MAX_RETRIES, retry_exceptions=False)(_shard_task)
        root = str(Path(root).resolve())
        pending = {task.options(num_cpus=threads).remote(s, root, threads): s for s in shards}
        done: dict = {}
        while pending:
            ready, _ = ray.wait(list(pending), num_returns=1)
            for ref in ready:
                shard = pending.pop(ref)
                try:
                    done[id(shard)] = Path(ray.get(ref))
                except ray.exceptions.RayError as e:
                    raise DatasetError(f"shard {shard.dataset_type}/{shard.task.folder} failed "
                                       f"after {MAX_RETRIES} retries: {e}") from None
                if progress:
                    progress(f"ray: {shard.dataset_type}/{shard.task.folder} written "
                             f"({len(done)}/{len(shards)})")
        return [done[id(s)] for s in shards]
    finally:
        ray.shutdown()
