"""The Linear Particle Chain impact damper (Gharib & Ghani, J. Sound Vib. 2013) from Python.

Three models of one system (``"reference"``: exact event-driven impulses; ``"rapier"``: the
Rapier contact solver; ``"compliant"``: Hertz contacts with Hunt-Crossley damping), one scene
format (the TOML files of ``scenes/``, or a dict with the same tables), and the studies of the
``lpc`` command line, returning NumPy arrays:

>>> import lpc_damper as lpc
>>> scene = lpc.load_scene("scenes/lpc-lsl.toml")
>>> run = lpc.run(scene)                      # run.t, run.xs, run.x (balls x samples), run.metrics
>>> table = lpc.ensemble(scene, 1000)         # dict of columns: member, drawn values, metrics
>>> import pandas; pandas.DataFrame(table)    # doctest: +SKIP

Every call that computes releases the GIL and runs its members or cells in parallel (rayon);
Ctrl-C stops a batch call between batches. ``lpc_damper.distributed`` runs ensembles and sweeps
on a Dask cluster with the same results. The physics and every rule are the library's
(docs/MODEL.md in the repository); errors carry the CLI's messages.
"""

from ._lpc_damper import (
    METRICS,
    MODELS,
    ModelError,
    Run,
    Scene,
    SceneError,
    __version__,
    chain,
    ensemble,
    frf,
    load_scene,
    run,
    sweep,
    sweep_cells,
)

__all__ = [
    "METRICS",
    "MODELS",
    "ModelError",
    "Run",
    "Scene",
    "SceneError",
    "__version__",
    "chain",
    "ensemble",
    "frf",
    "load_scene",
    "run",
    "sweep",
    "sweep_cells",
]


def _restore_scene(text: str, path: str, name: str) -> Scene:
    """Rebuilds a pickled :class:`Scene` (see ``Scene.__reduce__``)."""
    return Scene._restore(text, path, name)
