"""What the binding adds to a run, and Dask's throughput against rayon in one process.

    python python/benches/bench_binding.py overhead     # lpc_damper.run against the library call
    python python/benches/bench_binding.py dask         # 20 000-member ensemble: LocalCluster vs rayon

Recorded in docs/BENCHMARKS.md ("Python and Dask").
"""

from __future__ import annotations

import statistics
import sys
import time
from pathlib import Path

import lpc_damper as lpc

ROOT = Path(__file__).resolve().parents[2]
SCENE = ROOT / "scenes" / "lpc-lsl.toml"


def overhead(repeats: int = 2000) -> None:
    scene = lpc.load_scene(SCENE)
    for _ in range(50):
        lpc.run(scene)
    total, inner = [], []
    for _ in range(repeats):
        start = time.perf_counter()
        run = lpc.run(scene)
        total.append(time.perf_counter() - start)
        inner.append(run.wall_time_s)
    t, i = statistics.median(total), statistics.median(inner)
    print(f"lpc_damper.run: median {t * 1e6:.1f} us; the library call inside it (Run.wall_time_s): {i * 1e6:.1f} us; "
          f"the binding adds {(t - i) * 1e6:.1f} us = {100 * (t - i) / i:.1f} %")
    reading = []
    for _ in range(repeats // 4):
        run = lpc.run(scene)
        start = time.perf_counter()
        for name in ("t", "xs", "vs", "a", "x", "v", "impacts", "metrics", "energy", "noise"):
            getattr(run, name)
        reading.append(time.perf_counter() - start)
    r = statistics.median(reading)
    print(f"reading every series, the impacts and the summary once: median {r * 1e6:.1f} us more ({100 * r / i:.1f} % of the run)")


def dask(members: int = 20000) -> None:
    from dask.distributed import Client, LocalCluster

    from lpc_damper import distributed

    scene = lpc.load_scene(SCENE)
    lpc.ensemble(scene, 200)
    local = []
    for _ in range(5):
        start = time.perf_counter()
        lpc.ensemble(scene, members)
        local.append(time.perf_counter() - start)
    with LocalCluster(n_workers=2, threads_per_worker=1, processes=True, dashboard_address=None) as cluster, Client(cluster) as client:
        distributed.ensemble(scene, 200, client, chunk=100)
        for chunk in (None, 500, 1000, 2500, 5000, 10000):
            runs = []
            for _ in range(5):
                start = time.perf_counter()
                distributed.ensemble(scene, members, client, chunk=chunk)
                runs.append(time.perf_counter() - start)
            shown = chunk if chunk is not None else f"default ({distributed.default_chunk(1e-4, members, 2)} at 0.1 ms/member)"
            print(f"dask, chunk {shown}: best {min(runs):.3f} s, {min(local) / min(runs) * 100:.0f} % of rayon's throughput")
    print(f"rayon in one process (2 threads): best {min(local):.3f} s for {members} members")


if __name__ == "__main__":
    {"overhead": overhead, "dask": dask}[sys.argv[1] if len(sys.argv) > 1 else "overhead"]()
