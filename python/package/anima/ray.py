"""Controller optimisations whose evaluations run as Ray tasks.

An optimisation is thousands of independent evaluations; :func:`optimise` sends each generation's
candidates to Ray as tasks and tells the optimiser their fitnesses in candidate order. The optimiser is
seeded and draws every candidate before any is evaluated, so the result is bit-identical to
``Optimisation.run`` in one process, whatever the number of workers, and a run stopped mid-way resumes
from its log. The same code runs on a laptop (``ray.init()``) and on a cluster
(``ray.init(address="ray://head:10001")``): the objective travels to the workers as a pickled
:class:`anima.Evaluator`, so they need the ``anima`` package installed and no file of the spec's.
"""

from __future__ import annotations

import os
from typing import Callable, Optional, Union

import numpy as np

from ._anima import Evaluator, Optimisation

__all__ = ["optimise"]

PathLike = Union[str, "os.PathLike[str]"]

_remote_evaluate = None


def _evaluate(evaluator: Evaluator, x: np.ndarray) -> float:
    return evaluator(x)


def _task():
    """The remote form of :func:`_evaluate`, made once Ray is imported (so that importing this module
    does not need Ray)."""
    global _remote_evaluate
    if _remote_evaluate is None:
        import ray

        _remote_evaluate = ray.remote(num_cpus=1)(_evaluate)
    return _remote_evaluate


def optimise(
    spec: Union[PathLike, Optimisation],
    budget: Optional[int] = None,
    *,
    log: Optional[PathLike] = None,
    on_generation: Optional[Callable[[Optimisation], None]] = None,
) -> Optimisation:
    """Runs an optimisation spec to ``budget`` evaluations (the spec's by default) on Ray.

    ``spec`` is a spec file (``assets/optimisations/*.ron``) or an :class:`Optimisation` built from
    one. With ``log``, the log is written there (whole) after every generation, and an earlier log of
    the same spec found there is replayed first, so that a stopped run goes on where it stopped.
    ``on_generation`` sees the optimisation after every generation. Ray is started locally when it is
    not running yet (``ray.init()``); start it yourself to use a cluster.
    """
    import ray

    if not ray.is_initialized():
        ray.init()
    opt = spec if isinstance(spec, Optimisation) else Optimisation(os.fspath(spec))
    if log is not None and os.path.exists(log) and opt.evaluations == 0:
        opt.resume(os.fspath(log))
    budget = opt.budget if budget is None else budget
    evaluator = ray.put(opt.evaluator())
    task = _task()
    while opt.evaluations < budget:
        candidates = opt.ask()
        if candidates is None:
            break
        fitness = ray.get([task.remote(evaluator, x) for x in candidates])
        opt.tell([float(f) for f in fitness])
        if log is not None:
            opt.save_log(os.fspath(log))
        if on_generation is not None:
            on_generation(opt)
    return opt
