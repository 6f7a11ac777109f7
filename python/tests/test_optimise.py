"""Optimisations driven by ask/tell from Python equal the optimiser's own run, and resume from logs."""

import pickle
import re

import numpy as np

import anima

BUDGET = 16  # two CMA-ES generations of eight walks of 50 s


def spec(assets):
    return assets / "optimisations/walk-cmaes.ron"


def test_ask_tell_by_hand_equals_the_in_process_run(assets):
    own = anima.Optimisation(spec(assets))
    own.run(BUDGET)
    by_hand = anima.Optimisation(spec(assets))
    evaluate = by_hand.evaluator()
    while by_hand.evaluations < BUDGET:
        candidates = by_hand.ask()
        assert candidates.shape == (8, 4)
        by_hand.tell([evaluate(x) for x in candidates[::-1]][::-1])  # any order of evaluation
    assert by_hand.log_ron() == own.log_ron()
    x, f = own.best
    assert x.shape == (4,) and f > 0


def test_an_evaluator_survives_pickling_bit_for_bit(assets):
    opt = anima.Optimisation(spec(assets))
    x = opt.ask()[3]
    evaluate = opt.evaluator()
    again = pickle.loads(pickle.dumps(evaluate))
    assert np.float64(again(x)).tobytes() == np.float64(evaluate(x)).tobytes()


def test_a_stopped_run_resumes_from_its_log(assets, tmp_path):
    log = tmp_path / "walk-cmaes.log.ron"
    first = anima.Optimisation(spec(assets))
    first.run(8)
    first.save_log(log)
    resumed = anima.Optimisation(spec(assets))
    resumed.resume(log)
    assert resumed.evaluations == 8
    resumed.run(BUDGET)
    whole = anima.Optimisation(spec(assets))
    whole.run(BUDGET)
    assert resumed.log_ron() == whole.log_ron()


def test_telling_the_wrong_number_of_fitnesses_is_refused(assets):
    opt = anima.Optimisation(spec(assets))
    opt.ask()
    try:
        opt.tell([1.0, 2.0])
    except ValueError as e:
        assert "expected 8 fitnesses" in str(e)
    else:
        raise AssertionError("tell accepted 2 fitnesses for 8 candidates")
    opt.tell([1.0] * 8)  # the generation is still there to tell
    assert opt.evaluations == 8


def test_telling_a_fitness_that_is_not_finite_is_refused(assets):
    opt = anima.Optimisation(spec(assets))
    opt.ask()
    for bad in (float("nan"), float("inf"), float("-inf")):
        try:
            opt.tell([bad] * 8)
        except ValueError as e:
            assert "finite" in str(e)
        else:
            raise AssertionError(f"tell accepted {bad} fitnesses")
    opt.tell([1.0] * 8)  # the generation is still there to tell
    assert opt.evaluations == 8


def test_a_log_that_fails_to_replay_leaves_the_optimisation_fresh(assets, tmp_path):
    # Two generations told by hand (no walks), then the second one's first point edited: the replay
    # tells the first generation before it finds the difference.
    first = anima.Optimisation(spec(assets))
    for f in (1.0, 2.0):
        first.ask()
        first.tell([f] * 8)
    text = first.log_ron()
    second = r"(generation: 1,\s*stage: \d+,\s*x: \[\s*)[-+0-9.eE]+"
    edited = re.sub(second, r"\g<1>0.123456789", text, count=1)
    assert edited != text
    log = tmp_path / "edited.log.ron"
    log.write_text(edited)
    resumed = anima.Optimisation(spec(assets))
    try:
        resumed.resume(log)
    except ValueError as e:
        assert "evaluation 8" in str(e)
    else:
        raise AssertionError("an edited log was resumed")
    assert resumed.evaluations == 0
    fresh = anima.Optimisation(spec(assets))
    assert np.array_equal(resumed.ask(), fresh.ask())


def test_a_budget_beyond_the_limit_is_refused(assets):
    import pytest

    o = anima.Optimisation(spec(assets))
    with pytest.raises(ValueError, match="anima's limit"):
        o.run(10**7)
    with pytest.raises(ValueError, match="anima's limit"):
        o.run(0)
    assert o.evaluations == 0
