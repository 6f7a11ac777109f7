"""Times the thesis's walker under CMA-ES on a local Ray cluster of one and of two workers, and in one
process, alternately, and writes docs/python-ray.md.

    target/python/bin/python python/examples/ray_speedup.py      # after `cargo xtask test --python`

Each configuration runs the same optimisation (assets/optimisations/walk-cmaes.ron: 48 walks of 50 s in
six generations of eight); every run's log must equal the in-process one, bit for bit, or the script
stops. Times are of the optimisation only (Ray's start-up is timed apart), medians of the repeats with
min-max, on whatever else the machine is doing.
"""

from __future__ import annotations

import datetime
import os
import platform
import statistics
import sys
import tempfile
import time
from pathlib import Path

import ray

import anima
import anima.ray

ROOT = Path(__file__).resolve().parents[2]
SPEC = ROOT / "assets/optimisations/walk-cmaes.ron"
REPEATS = 3


def in_process() -> tuple[float, str]:
    opt = anima.Optimisation(SPEC)
    start = time.perf_counter()
    opt.run()
    return time.perf_counter() - start, opt.log_ron()


def on_ray(workers: int) -> tuple[float, float, str]:
    start = time.perf_counter()
    ray.init(num_cpus=workers, include_dashboard=False, log_to_driver=False)
    # One task per worker first, so that the workers are up and have imported anima before the clock.
    ray.get([anima.ray._task().remote(anima.Optimisation(SPEC).evaluator(), [0.25] * 4) for _ in range(workers)])
    started = time.perf_counter() - start
    start = time.perf_counter()
    opt = anima.ray.optimise(SPEC)
    took = time.perf_counter() - start
    ray.shutdown()
    return took, started, opt.log_ron()


def span(xs: list[float]) -> str:
    return f"{statistics.median(xs):.2f} s ({min(xs):.2f}-{max(xs):.2f})"


def main() -> None:
    times: dict[str, list[float]] = {"in-process": [], "ray-1": [], "ray-2": []}
    startup: dict[str, list[float]] = {"ray-1": [], "ray-2": []}
    reference = None
    for r in range(REPEATS):
        for name in ("ray-1", "ray-2", "in-process"):
            if name == "in-process":
                took, log = in_process()
            else:
                took, started, log = on_ray(int(name[-1]))
                startup[name].append(started)
            reference = reference or log
            if log != reference:
                sys.exit(f"{name}: the log differs from the first run's")
            times[name].append(took)
            print(f"repeat {r + 1}: {name} {took:.2f} s", flush=True)
    m = {k: statistics.median(v) for k, v in times.items()}
    evaluations = reference.count("fitness:")
    lines = [
        "# anima on Ray: the walker's CMA-ES on one and two workers",
        "",
        "Written by `target/python/bin/python python/examples/ray_speedup.py` (after `cargo xtask test "
        "--python`, which installs the package and Ray there); do not edit by hand.",
        "",
        f"Machine: {platform.machine()}, {os.cpu_count()} logical CPUs, Python {platform.python_version()}, "
        f"Ray {ray.__version__}, anima {anima.__version__}; {datetime.date.today().isoformat()}. "
        "The machine is shared: the other runs on it add noise.",
        "",
        f"The optimisation: `assets/optimisations/walk-cmaes.ron`, {evaluations} evaluations (walks of "
        "1000 control steps, 50 s) in generations of eight. Every run's log was equal, bit for bit, to the "
        f"first run's. Medians of {REPEATS} runs, min-max in brackets, the three configurations alternated.",
        "",
        "| configuration | optimisation | speed-up over one worker | Ray start-up |",
        "|---|---|---|---|",
        f"| Ray, 1 worker (`ray.init(num_cpus=1)`) | {span(times['ray-1'])} | 1.00 | {span(startup['ray-1'])} |",
        f"| Ray, 2 workers (`ray.init(num_cpus=2)`) | {span(times['ray-2'])} | {m['ray-1'] / m['ray-2']:.2f} "
        f"| {span(startup['ray-2'])} |",
        f"| in one process (`Optimisation.run()`, rayon on all cores) | {span(times['in-process'])} | "
        f"{m['ray-1'] / m['in-process']:.2f} | — |",
        "",
    ]
    out = ROOT / "docs/python-ray.md"
    with tempfile.NamedTemporaryFile("w", dir=out.parent, delete=False, suffix=".tmp") as f:
        f.write("\n".join(lines))
    os.replace(f.name, out)
    print("\n".join(lines))


if __name__ == "__main__":
    main()
