"""Ensembles and sweeps on a Dask cluster (a laptop's ``LocalCluster``, or Slurm/PBS through
dask-jobqueue), with results identical to the local call's.

The work is split into chunks of consecutive members (or cells); each chunk is one task that
runs :func:`lpc_damper.ensemble` (or :func:`lpc_damper.sweep`) on its range on a worker, and the
chunks' tables are joined in order. Member ``k``'s draws depend only on ``(seed, k)``, so the
table is the same, to the bit, whatever the chunking, the number of workers, or a local run.
A task is a pure function of its arguments: when a worker dies, Dask runs its chunks again
elsewhere, and since every chunk's rows are gathered once by its position, nothing is lost or
counted twice.

A Dask task costs about a millisecond of scheduling, so by default a chunk carries about
``seconds_per_chunk`` (one second) of work, estimated from one run of the nominal scene, but no
more than a quarter of one worker's share, so that every worker has several chunks to balance.
"""

from __future__ import annotations

import os
import time
from typing import Any, Sequence

import numpy as np

from . import _lpc_damper as _native

__all__ = ["ensemble", "sweep", "chunk_ranges", "default_chunk"]

Columns = dict[str, np.ndarray]


def chunk_ranges(count: int, chunk: int) -> list[tuple[int, int]]:
    """Consecutive ``(start, stop)`` ranges of at most ``chunk`` items covering ``range(count)``."""
    if count < 1:
        raise _native.SceneError(f"count: must be at least 1 (got {count})")
    if chunk < 1:
        raise _native.SceneError(f"chunk: must be at least 1 (got {chunk})")
    return [(start, min(start + chunk, count)) for start in range(0, count, chunk)]


def _workers(client: Any) -> int:
    try:
        return max(1, sum(w.get("nthreads", 1) for w in client.scheduler_info()["workers"].values()))
    except Exception:  # a client without scheduler info: assume one
        return 1


def default_chunk(
    seconds_per_item: float, count: int, workers: int, seconds_per_chunk: float = 1.0
) -> int:
    """Items per chunk: about ``seconds_per_chunk`` of work, at most a quarter of one worker's
    share of ``count`` (so that chunks balance), at least one."""
    by_time = seconds_per_chunk / max(seconds_per_item, 1e-9)
    by_share = count / (4 * max(workers, 1))
    return max(1, int(min(by_time, max(by_share, 1))))


def _cost_of_one(scene: _native.Scene, model: str, settings: dict[str, Any]) -> float:
    """Seconds of one run of the nominal scene (metrics only), measured here."""
    start = time.perf_counter()
    _native.ensemble(scene, 1, model=model, **settings)
    return time.perf_counter() - start


def _join(parts: Sequence[Columns]) -> Columns:
    keys = list(parts[0].keys())
    return {k: np.concatenate([p[k] for p in parts]) for k in keys}


def _ensemble_chunk(
    scene: _native.Scene,
    members: int,
    start: int,
    stop: int,
    seed: int | None,
    model: str,
    out: str | None,
    settings: dict[str, Any],
) -> Columns:
    return _native.ensemble(scene, members, seed=seed, model=model, start=start, stop=stop, out=out, **settings)


def ensemble(
    scene: _native.Scene,
    members: int,
    client: Any,
    *,
    seed: int | None = None,
    model: str = "reference",
    chunk: int | None = None,
    seconds_per_chunk: float = 1.0,
    out: str | os.PathLike[str] | None = None,
    **settings: Any,
) -> Columns:
    """:func:`lpc_damper.ensemble` of ``members`` members, in chunks of ``chunk`` members (by
    default about ``seconds_per_chunk`` of work each) on the Dask ``client``'s workers.

    Returns the same dict of columns as the local call, sorted by member. With ``out``, each
    chunk also writes ``part-START-STOP.parquet`` into that directory (one dataset for pandas,
    polars or Dask). ``settings`` are :func:`lpc_damper.ensemble`'s keywords (``horizon``, ...).
    """
    if chunk is None:
        chunk = default_chunk(_cost_of_one(scene, model, settings), members, _workers(client), seconds_per_chunk)
    ranges = chunk_ranges(members, chunk)
    out = os.fspath(out) if out is not None else None
    # The scene travels with each task (a kilobyte of TOML), rebuilt and validated there.
    futures = [
        client.submit(_ensemble_chunk, scene, members, start, stop, seed, model, out, settings, pure=False)
        for start, stop in ranges
    ]
    return _join(client.gather(futures))


def _sweep_chunk(
    scene: _native.Scene,
    axes: list[str] | None,
    start: int,
    stop: int,
    model: str,
    out: str | None,
    settings: dict[str, Any],
) -> Columns:
    return _native.sweep(scene, axes, model=model, start=start, stop=stop, out=out, **settings)


def sweep(
    scene: _native.Scene,
    client: Any,
    axes: Sequence[str] | None = None,
    *,
    model: str = "reference",
    chunk: int | None = None,
    seconds_per_chunk: float = 1.0,
    out: str | os.PathLike[str] | None = None,
    **settings: Any,
) -> Columns:
    """:func:`lpc_damper.sweep` over the scene's ``[sweep]`` or ``axes``, in chunks of ``chunk``
    cells on the Dask ``client``'s workers; the same dict of columns as the local call, sorted
    by cell. ``out`` writes one Parquet file per chunk, as :func:`ensemble` does."""
    axes = list(axes) if axes is not None else None
    cells = _native.sweep_cells(scene, axes)
    if chunk is None:
        chunk = default_chunk(_cost_of_one(scene, model, settings), cells, _workers(client), seconds_per_chunk)
    out = os.fspath(out) if out is not None else None
    futures = [
        client.submit(_sweep_chunk, scene, axes, start, stop, model, out, settings, pure=False)
        for start, stop in chunk_ranges(cells, chunk)
    ]
    return _join(client.gather(futures))
