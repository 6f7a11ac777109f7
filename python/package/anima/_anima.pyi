"""Type stubs of ``anima._anima``, the compiled half of the package (``python/src/lib.rs``)."""

from __future__ import annotations

import os
from typing import Optional, Sequence, Union

import numpy as np
import numpy.typing as npt

__version__: str

PathLike = Union[str, os.PathLike[str]]
Points = npt.NDArray[np.float64]
Triangles = npt.NDArray[np.uint32]

class SceneError(ValueError):
    """A scene, controller, optimisation or log file anima cannot read; the message names the file,
    the line and column, what was expected and what was found."""

class SimulationError(RuntimeError):
    """A simulation that cannot go on: a non-finite state (the message names the step where it
    appeared) or a solve that failed."""

class Cloth:
    """A cloth of any kind anima simulates, to step from Python. Arrays are ``(n, 3)`` float64 in the
    scene's axes (z up for sheets and drapes, y up for FLEX3D scripts)."""

    @staticmethod
    def sheet(
        n: int = 64,
        integrator: Optional[str] = None,
        dt: Optional[float] = None,
        duration: Optional[float] = None,
    ) -> Cloth:
        """The standard benchmark sheet, ``n`` x ``n`` particles on a 1 m square pinned at two corners."""
    @staticmethod
    def drape(
        test: str,
        vertices_per_side: int = 17,
        integrator: Optional[str] = None,
        dt: Optional[float] = None,
        duration: Optional[float] = None,
    ) -> Cloth:
        """Oliveira 2013's ``"table"`` (Test II) or ``"sphere"`` (Test III) drape."""
    @property
    def kind(self) -> str:
        """``sheet``, ``flex3d`` or ``oliveira``."""
    @property
    def n(self) -> int:
        """Particles now."""
    @property
    def time(self) -> float:
        """Simulated time, s."""
    @property
    def steps(self) -> int:
        """Steps taken."""
    @property
    def dt(self) -> float:
        """The next step, s."""
    @property
    def duration(self) -> float:
        """The scene's duration, s."""
    def step(self, n: int = 1) -> None:
        """Takes ``n`` steps (the GIL released); raises ``SimulationError`` at a non-finite state."""
    def run(self, t: Optional[float] = None) -> None:
        """Steps until the simulated time reaches ``t`` (the scene's duration by default)."""
    @property
    def positions(self) -> Points:
        """Positions, m (a copy)."""
    @property
    def velocities(self) -> Points:
        """Velocities, m/s (a copy)."""
    def read_positions(self, out: Points) -> None:
        """Writes the positions into ``out`` (C-contiguous, ``(n, 3)``), allocating nothing."""
    def read_velocities(self, out: Points) -> None:
        """Writes the velocities into ``out`` (C-contiguous, ``(n, 3)``), allocating nothing."""
    def set_state(self, positions: Points, velocities: Optional[Points] = None) -> None:
        """Replaces the positions (and the velocities, when given), read in place."""
    @property
    def triangles(self) -> Triangles:
        """The cloth's triangles, ``(m, 3)`` particle indices."""
    def obstacles(self) -> list[tuple[Points, Triangles]]:
        """The static objects as ``(vertices, triangles)`` pairs."""

class Figure:
    """Planar articulated figures (x-y plane, y up) of a body or character scene."""

    @property
    def time(self) -> float: ...
    @property
    def dt(self) -> float:
        """The control step, s."""
    @property
    def duration(self) -> float: ...
    def step(self, n: int = 1) -> None:
        """Takes ``n`` control steps."""
    @property
    def poses(self) -> Points:
        """``(bodies, 3)``: each body's centre x, y (m) and angle about z (rad)."""
    @property
    def body_names(self) -> list[str]:
        """``model/body`` for every row of ``poses``."""

class Evaluator:
    """An optimisation's objective, picklable: ``evaluator(x)`` is the fitness of ``x``."""

    def __call__(self, x: Sequence[float]) -> float: ...

class Optimisation:
    """A controller optimisation from a spec file, driven by ask/tell."""

    def __init__(self, spec: PathLike) -> None: ...
    @property
    def name(self) -> str: ...
    @property
    def budget(self) -> int:
        """The spec's evaluation budget."""
    @property
    def names(self) -> list[str]:
        """The free parameters' names."""
    @property
    def evaluations(self) -> int:
        """Evaluations told so far."""
    def ask(self) -> Optional[npt.NDArray[np.float64]]:
        """The next generation, ``(lambda, d)``, or ``None`` when finished."""
    def tell(self, fitness: Sequence[float]) -> None:
        """The generation's fitnesses, in candidate order."""
    def evaluator(self) -> Evaluator: ...
    def run(self, budget: Optional[int] = None) -> None:
        """Runs in this process, on all cores, to ``budget`` evaluations."""
    @property
    def best(self) -> Optional[tuple[npt.NDArray[np.float64], float]]: ...
    def log_ron(self) -> str: ...
    def save_log(self, path: PathLike) -> None: ...
    def resume(self, path: PathLike) -> None: ...

def load(path: PathLike, gravity: Optional[Sequence[float]] = None) -> Union[Cloth, Figure]:
    """Loads a scene file of any kind."""

def run_json(
    path: PathLike,
    out: Optional[PathLike] = None,
    integrator: Optional[str] = None,
    dt: Optional[float] = None,
    duration: Optional[float] = None,
    export: Optional[str] = None,
) -> str: ...
def walk_json(controller: PathLike, iterations: int = 1000) -> str: ...
