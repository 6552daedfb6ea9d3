"""Ensembles and sweeps on a Dask LocalCluster of two single-threaded worker processes: the
same table as the local call, whatever the chunking, with Parquet parts that read back as one
dataset, and nothing lost or counted twice when a worker is killed mid-run."""

from __future__ import annotations

import os
import signal
import threading
import time

import dask.distributed as dask_distributed
import numpy as np
import pytest

import lpc_damper as lpc
from lpc_damper import distributed


@pytest.fixture(scope="module")
def client():
    cluster = dask_distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True, dashboard_address=None)
    c = dask_distributed.Client(cluster)
    yield c
    c.close()
    cluster.close()


def assert_same_table(a, b):
    assert list(a) == list(b)
    for name in a:
        assert a[name].dtype == b[name].dtype, name
        assert np.array_equal(a[name], b[name], equal_nan=True), name


def test_chunk_ranges_cover_once():
    assert distributed.chunk_ranges(10, 4) == [(0, 4), (4, 8), (8, 10)]
    assert distributed.chunk_ranges(3, 10) == [(0, 3)]
    with pytest.raises(lpc.SceneError, match="chunk"):
        distributed.chunk_ranges(3, 0)
    # About a second of work, and at least four chunks per worker.
    assert distributed.default_chunk(1e-4, 20000, 2) == 2500
    assert distributed.default_chunk(0.5, 20000, 2) == 2
    assert distributed.default_chunk(10.0, 5, 2) == 1


def test_cluster_ensemble_equals_the_local_one_whatever_the_chunking(client, scenes):
    scene = lpc.load_scene(scenes / "lpc-lsl.toml")
    local = lpc.ensemble(scene, 500, seed=3)
    for chunk in (None, 1000, 37, 1):
        if chunk == 1:
            got = distributed.ensemble(scene, 20, client, seed=3, chunk=1)
            assert_same_table(got, lpc.ensemble(scene, 20, seed=3))
        else:
            assert_same_table(distributed.ensemble(scene, 500, client, seed=3, chunk=chunk), local)


def test_cluster_ensemble_of_the_contact_model(client, scenes):
    scene = lpc.load_scene(scenes / "lpc-lsl.toml")
    local = lpc.ensemble(scene, 6, model="compliant", horizon=0.5)
    assert_same_table(distributed.ensemble(scene, 6, client, model="compliant", chunk=2, horizon=0.5), local)


def test_cluster_sweep_equals_the_local_one(client, scenes):
    scene = lpc.load_scene(scenes / "lpc-lsl.toml")
    axes = ["gap=0.1 Rr,0.25 Rr,0.5 Rr", "restitution=0.3,0.6,0.9"]
    local = lpc.sweep(scene, axes)
    assert_same_table(distributed.sweep(scene, client, axes, chunk=2), local)
    assert_same_table(distributed.sweep(lpc.load_scene(scenes / "sweep-gap.toml"), client), lpc.sweep(lpc.load_scene(scenes / "sweep-gap.toml")))


def test_parquet_parts_read_back_as_one_dataset(client, scenes, tmp_path):
    import pandas as pd

    scene = lpc.load_scene(scenes / "lpc-lsl.toml")
    local = lpc.ensemble(scene, 120)
    distributed.ensemble(scene, 120, client, chunk=25, out=tmp_path / "parts")
    parts = sorted(p.name for p in (tmp_path / "parts").iterdir())
    assert parts == [f"part-{a:09d}-{b:09d}.parquet" for a, b in distributed.chunk_ranges(120, 25)]
    frame = pd.read_parquet(tmp_path / "parts").sort_values("member").reset_index(drop=True)
    assert set(frame["model"]) == {"reference"} and set(frame["seed"]) == {1} and set(frame["version"]) == {lpc.__version__}
    for name, values in local.items():
        assert np.array_equal(frame[name].to_numpy(dtype=values.dtype, na_value=np.nan), values, equal_nan=True), name


def test_a_killed_worker_loses_nothing(client, scenes):
    scene = lpc.load_scene(scenes / "lpc-lsl.toml")
    members, chunk = 30000, 1000
    local = lpc.ensemble(scene, members)
    pids = client.run(os.getpid)
    state = {}

    def kill_one_when_busy():
        deadline = time.time() + 60
        while time.time() < deadline:
            busy = {w: tasks for w, tasks in client.processing().items() if tasks}
            if busy:
                worker = next(iter(busy))
                state["pending_at_kill"] = sum(len(t) for t in client.processing().values())
                state["killed"] = worker
                os.kill(pids[worker], signal.SIGKILL)
                return
            time.sleep(0.005)

    killer = threading.Thread(target=kill_one_when_busy)
    killer.start()
    got = distributed.ensemble(scene, members, client, chunk=chunk)
    killer.join()
    assert state.get("killed"), "no worker was busy to kill"
    assert state["pending_at_kill"] > 0
    with pytest.raises(ProcessLookupError):
        os.kill(pids[state["killed"]], 0)
    assert_same_table(got, local)
    assert len(np.unique(got["member"])) == members
