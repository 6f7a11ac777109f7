"""Ctrl-C during a long call raises KeyboardInterrupt within a fraction of a second, and leaves what
the call was working on usable: a cloth at its last whole step, an optimisation where its log ends."""

import _thread
import faulthandler
import threading
import time

import numpy as np
import pytest

import anima

# Python's Ctrl-C, sent from another thread (the signal handler runs on the main thread).
AFTER_S = 0.5
# What "within a fraction of a second" is allowed here: the poll is 50 ms, a sheet step is microseconds,
# a control step milliseconds, and a shared CI machine is slow.
ANSWERED_WITHIN_S = 5.0


def interrupted(call):
    """Runs `call`, presses Ctrl-C after AFTER_S, and returns the seconds it took to raise. A call that
    ignores Ctrl-C would never return: past a minute the process is ended with every thread's traceback,
    so the test fails instead of hanging the test run."""
    timer = threading.Timer(AFTER_S, _thread.interrupt_main)
    faulthandler.dump_traceback_later(60, exit=True)
    start = time.monotonic()
    timer.start()
    try:
        with pytest.raises(KeyboardInterrupt):
            call()
    finally:
        timer.cancel()
        faulthandler.cancel_dump_traceback_later()
    return time.monotonic() - start


def test_a_long_cloth_run_answers_ctrl_c_and_keeps_its_last_step():
    cloth = anima.Cloth.sheet(n=16)
    took = interrupted(lambda: cloth.run(1e6))
    assert took < AFTER_S + ANSWERED_WITHIN_S, took
    assert 0 < cloth.steps and cloth.time < 1e6
    t = cloth.time
    cloth.step(3)
    assert cloth.time > t, "the cloth steps on after the interrupt"

    took = interrupted(lambda: cloth.step(10**15))
    assert took < AFTER_S + ANSWERED_WITHIN_S, took


def test_a_long_walk_answers_ctrl_c(assets):
    took = interrupted(lambda: anima.walk(assets / "controllers/walk-robust.ron", iterations=2**62))
    assert took < AFTER_S + ANSWERED_WITHIN_S, took


def test_an_interrupted_optimisation_goes_on_where_its_log_ends(assets, tmp_path):
    spec = assets / "optimisations/walk-cmaes.ron"
    opt = anima.Optimisation(spec)
    took = interrupted(lambda: opt.run())
    assert took < AFTER_S + ANSWERED_WITHIN_S, took
    # Only whole generations are logged, and the optimiser stands where its log ends: it asks what an
    # optimisation resumed from that log asks (the generation cut short, again).
    assert opt.evaluations % 8 == 0
    replay = anima.Optimisation(spec)
    if opt.evaluations > 0:
        log = tmp_path / "walk-cmaes.log.ron"
        opt.save_log(log)
        replay.resume(log)
    np.testing.assert_array_equal(opt.ask(), replay.ask())
