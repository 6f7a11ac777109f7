"""The optimisation distributed over a local Ray cluster gives the in-process result, bit for bit."""

import pytest

import anima

ray = pytest.importorskip("ray", reason="anima.ray needs Ray (pip install 'anima[ray]')")

BUDGET = 16


@pytest.fixture(scope="module")
def cluster():
    # A local cluster of two CPUs: two evaluations run at once.
    ray.init(num_cpus=2, include_dashboard=False, log_to_driver=False)
    yield
    ray.shutdown()


def test_ray_gives_the_in_process_result(assets, cluster):
    import anima.ray

    spec = assets / "optimisations/walk-cmaes.ron"
    distributed = anima.ray.optimise(spec, BUDGET)
    local = anima.Optimisation(spec)
    local.run(BUDGET)
    assert distributed.evaluations == BUDGET
    assert distributed.log_ron() == local.log_ron()


def test_a_ray_run_resumes_from_its_log(assets, tmp_path, cluster):
    import anima.ray

    spec = assets / "optimisations/walk-cmaes.ron"
    log = tmp_path / "walk-cmaes.log.ron"
    anima.ray.optimise(spec, 8, log=log)
    seen = []
    resumed = anima.ray.optimise(spec, BUDGET, log=log, on_generation=lambda o: seen.append(o.evaluations))
    assert seen == [16]  # only the second generation was evaluated again
    whole = anima.Optimisation(spec)
    whole.run(BUDGET)
    assert resumed.log_ron() == whole.log_ron()
    assert log.read_text() == whole.log_ron()
