"""anima: physically based animation — cloth and articulated characters driven by controllers.

The simulations are anima's Rust crates; this package steps them from Python with NumPy arrays in and
out::

    import anima
    cloth = anima.Cloth.sheet(n=32)          # the standard benchmark sheet, 32 x 32
    cloth.run(0.5)                           # half a second, the GIL released
    x = cloth.positions                      # (n, 3) float64, metres

Files load with :func:`load` (any scene anima runs: ``.par`` scripts and ``.ron`` scenes), whole runs
go through :func:`run` (what ``anima run`` does, returning its summary as a dict), and controller
optimisations are driven by :class:`Optimisation` — in this process, or over a Ray cluster with
:func:`anima.ray.optimise`.
"""

from __future__ import annotations

import json
import os
from typing import Any, Optional, Union

from ._anima import (
    Cloth,
    Evaluator,
    Figure,
    Optimisation,
    SceneError,
    SimulationError,
    __version__,
    load,
)
from . import _anima

__all__ = [
    "Cloth",
    "Evaluator",
    "Figure",
    "Optimisation",
    "SceneError",
    "SimulationError",
    "__version__",
    "load",
    "run",
    "walk",
]

PathLike = Union[str, "os.PathLike[str]"]


def run(
    path: PathLike,
    out: Optional[PathLike] = None,
    *,
    integrator: Optional[str] = None,
    dt: Optional[float] = None,
    duration: Optional[float] = None,
    export: Optional[str] = None,
) -> dict[str, Any]:
    """Runs a scene file to its end, as ``anima run`` does, and returns its summary.

    With ``out``, the frames, pictures and ``summary.json`` are written there, and with
    ``export="gltf"`` the whole run as an animated glTF 2.0 file, ``animation.glb`` (``export="usd"``: an
    animated USD stage, ``animation.usda``). ``integrator``, ``dt``
    and ``duration`` override the scene's, as the command's options do. A character scene's summary
    holds its evaluation (a walk's distance, a throw's landing point, a backflip's outcome).
    """
    text = _anima.run_json(
        os.fspath(path),
        None if out is None else os.fspath(out),
        integrator=integrator,
        dt=dt,
        duration=duration,
        export=export,
    )
    return json.loads(text)


def walk(controller: PathLike, iterations: int = 1000) -> dict[str, Any]:
    """The thesis's walking evaluation of a controller file over ``iterations`` control steps.

    Returns the iterations simulated, the distance walked (m), whether the walker fell or stopped, and
    the thesis's fitness (the distance, or 0 after a fall or a stop).
    """
    return json.loads(_anima.walk_json(os.fspath(controller), iterations))
