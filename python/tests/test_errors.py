"""Errors arrive as Python exceptions with the file, line and column anima's messages name."""

import re

import pytest

import anima


def test_a_malformed_scene_names_file_line_and_column(tmp_path):
    bad = tmp_path / "bad.ron"
    bad.write_text("SheetScene(\n    sheet: SheetSpec(\n        n: sixty-four,\n")
    with pytest.raises(anima.SceneError) as caught:
        anima.load(bad)
    message = str(caught.value)
    assert "bad.ron" in message and re.search(r":3:\d+", message), message
    assert "expected" in message
    assert isinstance(caught.value, ValueError)


def test_a_malformed_script_names_its_line(tmp_path):
    bad = tmp_path / "bad.par"
    bad.write_text("OBJETO pano\nDIMENSAO 10 x 10\n")
    with pytest.raises(anima.SceneError, match=r"bad\.par:\d+:\d+"):
        anima.load(bad)


def test_a_missing_file_and_a_wrong_kind_are_scene_errors(assets, tmp_path):
    with pytest.raises(anima.SceneError, match="nothing-here.ron"):
        anima.load(tmp_path / "nothing-here.ron")
    with pytest.raises(anima.SceneError, match=r"\.par or \.ron"):
        anima.load(assets / "meshes/bunny.obj")


def test_a_bad_option_is_a_value_error():
    with pytest.raises(ValueError, match="integrator"):
        anima.Cloth.sheet(n=8, integrator="leapfrog-9")
    with pytest.raises(ValueError, match="dt"):
        anima.Cloth.sheet(n=8, dt=-1.0)
    with pytest.raises(ValueError, match="table"):
        anima.Cloth.drape("teapot")


def test_a_blow_up_names_the_step_where_it_appeared():
    # h·ω ≈ 11 on the stiffest spring: each step multiplies that mode by about 11.
    cloth = anima.Cloth.sheet(n=16, integrator="forward-euler", dt=0.01)
    with pytest.raises(anima.SimulationError, match=r"step \d+"):
        cloth.run(10.0)
    assert cloth.steps < 1000


def test_an_optimisation_log_of_another_spec_is_refused(assets, tmp_path):
    greedy = anima.Optimisation(assets / "optimisations/walk.ron")
    log = tmp_path / "greedy.log.ron"
    g = anima.Optimisation(assets / "optimisations/walk-cmaes.ron")
    g.ask()
    g.tell([1.0] * 8)
    g.save_log(log)
    with pytest.raises(ValueError, match="greedy.log.ron"):
        greedy.resume(log)


def test_a_controller_the_walker_cannot_bind_is_a_scene_error_at_its_line(assets, tmp_path):
    bad = tmp_path / "ctl.ron"
    text = (assets / "controllers/walk-optimised.ron").read_text()
    bad.write_text(text.replace('kind: "foot_up"', 'kind: "foot_upp"', 1))
    wanted = r"ctl\.ron: line 122, column \d+: .*unknown sensor kind `foot_upp`"
    with pytest.raises(anima.SceneError, match=wanted):
        anima.walk(bad, iterations=10)


def test_an_evaluator_restored_with_ids_its_controller_lacks_is_a_value_error(assets):
    evaluator = anima.Optimisation(assets / "optimisations/walk-cmaes.ron").evaluator()
    restore, (objective, ids, controller) = evaluator.__reduce__()
    assert restore(objective, ids, controller)([0.25] * len(ids)) >= 0.0
    with pytest.raises(ValueError, match="parameter id 1000000"):
        restore(objective, [10**6], controller)
