"""The binding against the CLI and the library's rules: same series to the bit, same errors,
same ensembles and sweeps, columns a DataFrame takes, and the GIL released while it computes."""

from __future__ import annotations

import csv
import pickle
import subprocess
import threading
import time
from pathlib import Path

import numpy as np
import pytest

import lpc_damper as lpc


def read_csv(path: Path) -> tuple[list[str], list[list[str]]]:
    with open(path, newline="") as f:
        rows = list(csv.reader(f))
    return rows[0], rows[1:]


def column(header: list[str], rows: list[list[str]], name: str) -> np.ndarray:
    j = header.index(name)
    return np.array([float(r[j]) if r[j] != "" else np.nan for r in rows])


@pytest.mark.parametrize("model", ["reference", "compliant"])
def test_run_equals_the_cli_series_to_the_last_bit(lpc_bin, scenes, tmp_path, model):
    subprocess.run([lpc_bin, "run", scenes / "lpc-lsl.toml", "--model", model, "--out", tmp_path], check=True, capture_output=True)
    header, rows = read_csv(tmp_path / "series.csv")
    run = lpc.run(lpc.load_scene(scenes / "lpc-lsl.toml"), model=model)
    # Rust writes the shortest string that reads back to the same double; float() reads it
    # exactly: equality is bit equality.
    for name, got in [("t", run.t), ("xs", run.xs), ("vs", run.vs), ("a", run.a)]:
        assert np.array_equal(column(header, rows, name), got), name
    assert run.x.shape == (3, len(rows)) and run.v.shape == (3, len(rows))
    for i in range(3):
        assert np.array_equal(column(header, rows, f"x{i + 1}"), run.x[i])
        assert np.array_equal(column(header, rows, f"v{i + 1}"), run.v[i])
    ih, irows = read_csv(tmp_path / "impacts.csv")
    assert np.array_equal(column(ih, irows, "t"), run.impacts["t"])
    assert list(run.impacts["body_a"]) == [r[ih.index("body_a")] for r in irows]
    import json

    summary = json.loads((tmp_path / "summary.json").read_text())
    assert run.metrics == summary["metrics"]
    assert run.energy == summary["energy"]
    assert run.noise == summary["noise"]


def test_series_arrays_are_float64_and_owned_by_numpy(scenes):
    run = lpc.run(lpc.load_scene(scenes / "lpc-lsl.toml"))
    for a in (run.t, run.xs, run.vs, run.a, run.x, run.v):
        assert a.dtype == np.float64 and a.flags["C_CONTIGUOUS"]
    assert run.t[0] == 0.0 and run.t[-1] == pytest.approx(5.0)


DROPPED_BALL = """
name = "dropped"
[frame]
mass = 1.35
stiffness = 865.0
damping = 1.092
initial_displacement = 0.0
[container]
length = 0.1
width = 0.06
height = 0.1
[world]
gravity = [0.0, 0.0, -9.81]
restitution = 0.8
[[ball]]
position = [0.05, 0.0, -0.005]
mass = 0.004
radius = 0.005
[run]
horizon = 1.5
"""


def test_balls_across_the_motion_are_arrays_equal_to_the_cli_series(lpc_bin, tmp_path):
    # A ball dropped 40 mm onto the floor (z = -0.05 m) of a container at rest comes to rest on it.
    path = tmp_path / "dropped.toml"
    path.write_text(DROPPED_BALL)
    subprocess.run([lpc_bin, "run", path, "--out", tmp_path / "out"], check=True, capture_output=True)
    header, rows = read_csv(tmp_path / "out" / "series.csv")
    run = lpc.run(lpc.load_scene(path))
    assert run.y.shape == run.x.shape == (1, len(rows)) and run.z.shape == run.x.shape
    assert run.y.dtype == np.float64 and run.z.flags["C_CONTIGUOUS"]
    assert np.array_equal(column(header, rows, "y1"), run.y[0])
    assert np.array_equal(column(header, rows, "z1"), run.z[0])
    assert run.z[0, 0] == -0.005 and run.z[0, -1] == pytest.approx(-0.045, abs=1e-15)
    assert np.all(run.z[0] >= -0.045 - 1e-12)


def test_balls_on_lines_have_no_coordinates_across(scenes):
    run = lpc.run(lpc.load_scene(scenes / "lpc-lsl.toml"))
    assert run.y is None and run.z is None


def test_a_bad_field_raises_scene_error_with_the_cli_message(lpc_bin, scenes, tmp_path):
    text = (scenes / "lpc-lsl.toml").read_text().replace("mass = 1.35", "mass = -1.35")
    bad = tmp_path / "bad.toml"
    bad.write_text(text)
    cli = subprocess.run([lpc_bin, "run", bad], capture_output=True, text=True)
    assert cli.returncode == 2
    with pytest.raises(lpc.SceneError) as e:
        lpc.load_scene(bad)
    assert "`frame.mass`" in str(e.value)
    assert str(e.value) in cli.stderr
    d = lpc.load_scene(scenes / "lpc-lsl.toml").to_dict()
    d["balls"]["restitution"] = float("nan")
    with pytest.raises(lpc.SceneError, match="balls.restitution"):
        lpc.Scene.from_dict(d)
    d = lpc.load_scene(scenes / "lpc-lsl.toml").to_dict()
    d["reference"] = {"contact_duration": 0.5}
    with pytest.raises(lpc.SceneError, match="reference.contact_duration"):
        lpc.Scene.from_dict(d)
    d = lpc.load_scene(scenes / "lpc-lsl.toml").to_dict()
    d["frame"]["colour"] = "red"
    with pytest.raises(lpc.SceneError, match="colour"):
        lpc.Scene.from_dict(d)
    with pytest.raises(lpc.SceneError, match="cannot read"):
        lpc.load_scene(tmp_path / "missing.toml")
    with pytest.raises(lpc.SceneError, match="model"):
        lpc.run(lpc.load_scene(scenes / "lpc-lsl.toml"), model="abaqus")
    with pytest.raises(lpc.SceneError, match="horizon"):
        lpc.run(lpc.load_scene(scenes / "lpc-lsl.toml"), horizon=-1.0)


def test_a_dict_scene_is_the_file_scene(scenes):
    scene = lpc.load_scene(scenes / "lpc-lsl.toml")
    d = scene.to_dict()
    assert d["tolerances"]["gap"] == "0.02 Rr"
    again = lpc.Scene.from_dict(d)
    assert again.to_dict() == d
    assert np.array_equal(lpc.run(again).xs, lpc.run(scene).xs)
    assert pickle.loads(pickle.dumps(scene)).to_dict() == d


def test_ensemble_equals_the_cli_members_table(lpc_bin, scenes, tmp_path):
    subprocess.run([lpc_bin, "run", scenes / "lpc-lsl.toml", "--ensemble", "40", "--seed", "7", "--out", tmp_path], check=True, capture_output=True)
    header, rows = read_csv(tmp_path / "members.csv")
    table = lpc.ensemble(lpc.load_scene(scenes / "lpc-lsl.toml"), 40, seed=7)
    assert list(table) == header
    assert table["member"].dtype == np.int64 and list(table["member"]) == list(range(40))
    for name in header:
        assert np.array_equal(column(header, rows, name), table[name].astype(float), equal_nan=True), name


def test_ensemble_ranges_are_the_members_of_the_whole(scenes):
    scene = lpc.load_scene(scenes / "lpc-lsl.toml")
    whole = lpc.ensemble(scene, 30)
    parts = [lpc.ensemble(scene, 30, start=a, stop=b) for a, b in [(0, 7), (7, 8), (8, 30)]]
    for name, values in whole.items():
        assert np.array_equal(np.concatenate([p[name] for p in parts]), values, equal_nan=True)


def test_sweep_and_dataframe(scenes):
    import pandas as pd

    scene = lpc.load_scene(scenes / "sweep-gap.toml")
    table = lpc.sweep(scene)
    frame = pd.DataFrame(table)
    assert list(frame.columns[:2]) == ["cell", "gap"] and len(frame) == lpc.sweep_cells(scene)
    assert list(frame["cell"]) == list(range(len(frame)))
    grid = lpc.sweep(lpc.load_scene(scenes / "lpc-lsl.toml"), ["gap=0.1 Rr,0.5 Rr", "restitution=0.5,0.9"])
    assert list(grid["restitution"]) == [0.5, 0.5, 0.9, 0.9] and list(grid["gap"]) == [0.1, 0.5, 0.1, 0.5]
    half = lpc.sweep(lpc.load_scene(scenes / "lpc-lsl.toml"), ["gap=0.1 Rr,0.5 Rr", "restitution=0.5,0.9"], start=2)
    assert np.array_equal(half["impact_count"], grid["impact_count"][2:])


def test_chain_ker_of_an_elastic_equal_chain_is_one(scenes, tmp_path):
    d = lpc.load_scene(scenes / "chain-ker.toml").to_dict()
    table = lpc.chain(lpc.load_scene(scenes / "chain-ker.toml"))
    assert set(table) == {"large", "small", "ker"}
    assert np.all((table["ker"] > 0) & (table["ker"] <= 1 + 1e-12))
    assert "chain" in d


def test_calls_release_the_gil(scenes):
    """A Python thread keeps running while an ensemble computes: it could not if the call
    held the GIL for its whole length."""
    scene = lpc.load_scene(scenes / "lpc-lsl.toml")
    ticks = [0]
    stop = threading.Event()

    def tick():
        while not stop.is_set():
            ticks[0] += 1
            time.sleep(0.001)

    t = threading.Thread(target=tick)
    t.start()
    time.sleep(0.01)
    try:
        before = ticks[0]
        lpc.ensemble(scene, 3000, model="reference", horizon=5.0)
        during = ticks[0] - before
    finally:
        stop.set()
        t.join()
    assert during > 5


def test_ctrl_c_stops_a_long_ensemble_between_batches(scenes, tmp_path):
    """SIGINT during a long call raises KeyboardInterrupt from inside it: the call stops, so
    the table it would have written at its end is never written (a call that ran to its end
    and raised only afterwards would have written it)."""
    import signal
    import sys

    script = tmp_path / "long.py"
    out = tmp_path / "parts"
    script.write_text(
        "import signal, sys, lpc_damper as lpc\n"
        # A process started in the background inherits SIGINT ignored, and Python then leaves
        # it so: ask for Python's own handler (KeyboardInterrupt), as a terminal would give.
        "signal.signal(signal.SIGINT, signal.default_int_handler)\n"
        f"scene = lpc.load_scene({str(scenes / 'lpc-lsl.toml')!r})\n"
        "print('started', flush=True)\n"
        f"lpc.ensemble(scene, 2000, model='compliant', out={str(out)!r})\n"
        "print('finished', flush=True)\n"
    )
    p = subprocess.Popen([sys.executable, str(script)], stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    assert p.stdout.readline().strip() == "started"
    time.sleep(0.5)
    p.send_signal(signal.SIGINT)
    stdout, stderr = p.communicate(timeout=600)
    assert "KeyboardInterrupt" in stderr
    assert "finished" not in stdout
    assert not out.exists()


def test_the_fig9_example_runs(tmp_path):
    """examples/fig9.py (the user guide's Python example) runs and draws its figure."""
    import os
    import sys

    root = Path(__file__).resolve().parents[2]
    out = tmp_path / "fig9.png"
    env = dict(os.environ, MPLBACKEND="Agg")
    done = subprocess.run([sys.executable, str(root / "examples" / "fig9.py"), str(out)], env=env, capture_output=True, text=True, cwd=tmp_path)
    assert done.returncode == 0, done.stderr
    assert out.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n" and out.stat().st_size > 10_000


def test_a_budget_stops_every_model_and_keeps_the_run_so_far(scenes):
    scene = lpc.load_scene(scenes / "lpc-lsl.toml")
    with pytest.raises(lpc.ModelError, match="--max-steps") as e:
        lpc.run(scene, model="compliant", max_steps=3000)
    partial = e.value.partial
    assert 0.0 < partial.horizon < 5.0 and partial.t[-1] <= partial.horizon
    # The run so far is a run: its energy balance closes to the integration tolerance.
    assert abs(partial.energy["balance_error"]) < 1e-6
    # Every model takes the budgets: the reference counts events.
    with pytest.raises(lpc.ModelError, match="the reference stopped") as e:
        lpc.run(scene, max_steps=10)
    assert 0.0 < e.value.partial.horizon < 5.0
    with pytest.raises(lpc.SceneError, match="max_wall_time"):
        lpc.run(scene, model="compliant", max_wall_time=-1.0)


def test_a_run_that_counts_its_impacts_keeps_the_same_account(scenes):
    """`impacts="count"` drops the list, not the physics: the same count, the same energy
    account and metrics as the run that keeps every impact; a bad choice is refused."""
    scene = lpc.load_scene(scenes / "planar-bed.toml")
    every = lpc.run(scene, horizon=0.05)
    counted = lpc.run(scene, horizon=0.05, impacts="count")
    assert counted.impact_count == every.impact_count == len(every.impacts["t"]) > 100
    assert len(counted.impacts["t"]) == 0
    assert counted.energy == every.energy and counted.metrics == every.metrics
    with pytest.raises(lpc.SceneError, match="impacts: must be `every` or `count`"):
        lpc.run(scene, impacts="some")


def test_studies_give_each_run_the_budget(scenes):
    """Every function that runs a model takes the budgets: a chain whose runs exceed one
    raises, a frequency response reports each frequency's stop, bad budgets are refused."""
    with pytest.raises(lpc.ModelError, match="--max-steps"):
        lpc.chain(lpc.load_scene(scenes / "chain-ker.toml"), max_steps=2)
    forced = lpc.load_scene(scenes / "forced-lsl.toml")
    response = lpc.frf(forced, [3.0], max_steps=5)
    assert np.isnan(response["amplitude"][0])
    for call in (
        lambda: lpc.frf(forced, [3.0], max_steps=0),
        lambda: lpc.sweep(lpc.load_scene(scenes / "sweep-gap.toml"), max_steps=0),
        lambda: lpc.ensemble(lpc.load_scene(scenes / "lpc-lsl.toml"), 2, max_wall_time=0.0),
    ):
        with pytest.raises(lpc.SceneError, match="max_steps|max_wall_time"):
            call()


def test_frf_needs_a_forced_scene_and_valid_frequencies(scenes):
    """Regression: `frf` on a scene without `[forcing]` panicked inside the library
    (PanicException); it is a SceneError, and each frequency keeps the file's rules."""
    with pytest.raises(lpc.SceneError, match="forcing"):
        lpc.frf(lpc.load_scene(scenes / "lpc-lsl.toml"), [3.0])
    forced = lpc.load_scene(scenes / "forced-lsl.toml")
    for bad in (-1.0, 0.0, float("nan")):
        with pytest.raises(lpc.SceneError, match=r"frequencies\[1\]"):
            lpc.frf(forced, [3.0, bad])


def test_each_damper_of_several_has_its_figures(scenes):
    """A run of several dampers gives each one's floor, balls, impacts and impact loss, as
    `summary.json`'s `dampers`; a scene of one damper has none."""
    two = lpc.load_scene(scenes.parent / "examples" / "scenes" / "dampers-two-floors.toml")
    r = lpc.run(two, model="rapier", horizon=0.5)
    assert [(d["damper"], d["floor"], d["balls"]) for d in r.dampers] == [(1, 2, 40), (2, 3, 40)]
    assert sum(d["impacts"] for d in r.dampers) == r.impact_count > 0
    losses = sum(d["impact_loss"] for d in r.dampers)
    assert losses == pytest.approx(float(np.sum(r.impacts["energy_lost"])), rel=1e-12)
    assert lpc.run(lpc.load_scene(scenes / "lpc-lsl.toml"), horizon=0.1).dampers == []
