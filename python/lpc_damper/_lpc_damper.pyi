"""Type stubs of the extension module (python/src/lib.rs)."""

from os import PathLike
from typing import Any, Literal, Mapping, Sequence

import numpy as np
import numpy.typing as npt

ModelName = Literal["reference", "rapier", "compliant"]
Columns = dict[str, npt.NDArray[Any]]

__version__: str
MODELS: list[str]
METRICS: list[str]

class SceneError(ValueError):
    """A scene (or a setting) that cannot exist; the message names the field and the rule."""

class ModelError(RuntimeError):
    """A model that could not finish a scene, with the reason; a budget stop of the compliant
    model carries the run so far as ``partial``."""

    partial: Run

class Scene:
    """A validated scene file: a damper scene or a chain experiment."""

    @staticmethod
    def load(path: str | PathLike[str]) -> Scene: ...
    @staticmethod
    def from_dict(d: Mapping[str, Any], name: str | None = None) -> Scene: ...
    def to_dict(self) -> dict[str, Any]: ...
    @property
    def name(self) -> str: ...
    @property
    def path(self) -> str: ...
    @property
    def is_chain(self) -> bool: ...
    @staticmethod
    def _restore(text: str, path: str, name: str) -> Scene: ...

class Run:
    """One run: series as NumPy arrays, impacts as a dict of arrays, summary dicts."""

    scene: str
    model: str
    horizon: float
    t: npt.NDArray[np.float64]
    xs: npt.NDArray[np.float64]
    vs: npt.NDArray[np.float64]
    a: npt.NDArray[np.float64]
    x: npt.NDArray[np.float64]
    v: npt.NDArray[np.float64]
    y: npt.NDArray[np.float64] | None
    z: npt.NDArray[np.float64] | None
    impacts: Columns
    impact_count: int
    metrics: dict[str, float | None]
    energy: dict[str, float]
    noise: dict[str, Any]
    dampers: list[dict[str, Any]]
    wall_time_s: float

def load_scene(path: str | PathLike[str]) -> Scene: ...
def run(
    scene: Scene,
    model: ModelName = "reference",
    *,
    horizon: float | None = None,
    sample_dt: float | None = None,
    stepping: Literal["aligned", "fixed"] | None = None,
    dt: float | None = None,
    solver_iterations: int | None = None,
    ccd: bool = False,
    tolerance: float | None = None,
    max_steps: int | None = None,
    max_wall_time: float | None = None,
    impacts: Literal["every", "count"] = "every",
) -> Run: ...
def ensemble(
    scene: Scene,
    members: int,
    *,
    seed: int | None = None,
    model: ModelName = "reference",
    start: int = 0,
    stop: int | None = None,
    out: str | PathLike[str] | None = None,
    horizon: float | None = None,
    sample_dt: float | None = None,
    stepping: Literal["aligned", "fixed"] | None = None,
    dt: float | None = None,
    solver_iterations: int | None = None,
    ccd: bool = False,
    tolerance: float | None = None,
    max_steps: int | None = None,
    max_wall_time: float | None = None,
) -> Columns: ...
def sweep_cells(scene: Scene, axes: Sequence[str] | None = None) -> int: ...
def sweep(
    scene: Scene,
    axes: Sequence[str] | None = None,
    *,
    model: ModelName = "reference",
    start: int = 0,
    stop: int | None = None,
    out: str | PathLike[str] | None = None,
    horizon: float | None = None,
    stepping: Literal["aligned", "fixed"] | None = None,
    dt: float | None = None,
    solver_iterations: int | None = None,
    ccd: bool = False,
    tolerance: float | None = None,
    max_steps: int | None = None,
    max_wall_time: float | None = None,
) -> Columns: ...
def frf(
    scene: Scene,
    frequencies: Sequence[float],
    *,
    model: ModelName = "reference",
    max_steps: int | None = None,
    max_wall_time: float | None = None,
) -> Columns: ...
def chain(
    scene: Scene,
    *,
    model: ModelName = "reference",
    max_steps: int | None = None,
    max_wall_time: float | None = None,
) -> Columns: ...
