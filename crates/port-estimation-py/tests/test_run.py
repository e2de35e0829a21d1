"""``run(us, ys)`` gives, for every estimator of the registry, exactly the numbers of the per-step
calls; it continues from the current state, so consecutive runs equal one run; its memory is
bounded."""

from __future__ import annotations

import numpy as np
import pytest
from conftest import on_boundary, random_system

import port_estimation as pe

ROWS = {row["name"]: row for row in pe.estimators()}


def _inside(rng, shape):
    return on_boundary(rng, shape) * rng.uniform() ** (1.0 / shape.shape[0])


def _case(row, model_kind, steps=80, seed=1):
    """An estimator of the registry row ``row`` on a model, and a log its noise bounds allow."""
    rng = np.random.default_rng(seed)
    if model_kind == "linear":
        a, b, c, q, r, p0 = random_system(rng, 3, 2, 2, diagonal_r=True)
        model = pe.Model(a, b, c)
    else:
        model = pe.Model.vessel()
        q, r, p0 = np.diag([1e-2, 1e-2, 1e-4, 1e-3, 1e-3, 1e-5]), np.diag([0.5, 0.5, 0.01]), np.eye(6) * 0.1
    n, p, m = model.dims
    x = np.zeros(n) if model_kind == "linear" else np.array([0.0, 0.0, 0.1, 1.0, 0.1, 0.01])
    x0 = x + _inside(rng, p0)
    us = rng.uniform(-1, 1, size=(steps, p)) * (1.0 if model_kind == "linear" else 2e5)
    ys = np.zeros((steps, m + row["extra_measurements"]))
    for k in range(steps):
        x = model.f(x, us[k]) + _inside(rng, q)
        ys[k, :m] = model.h(x, us[k]) + _inside(rng, r)
    if row["extra_measurements"]:  # the fuzzy-adaptive filter's [satellites, RTK code]
        ys[:, m] = rng.integers(4, 20, size=steps)
        ys[:, m + 1] = rng.choice([0, 1, 2, 3, 4], size=steps)
    settings = {}
    if "u_lower" in row["keywords"]:
        settings.update(u_lower=-np.ones(p), u_upper=np.ones(p))
    if "lambda_v" in row["keywords"]:  # the linear moving-horizon estimators need the noise boxes
        wq, wr = np.sqrt(np.diag(q)), np.sqrt(np.diag(r))
        settings.update(w_lower=-wq, w_upper=wq, v_lower=-wr, v_upper=wr)

    if row["kind"] == "guaranteed constrained zonotope":
        # Boxes: those around the noise ellipsoids, and an initial box that holds the true start
        # (the centre below is x0 / 2, off the vessel's start by up to 0.5 in its speed).
        p0, q, r = (np.sqrt(np.diag(s)) for s in (3.0 * p0, q, r))

    def build():
        return pe.Estimator(row["name"], model, x0=x0 * 0.5, P0=p0, Q=q, R=r, **settings)

    return build, us, ys


CASES = [(name, "linear") for name in ROWS] + [
    (name, "vessel") for name, row in ROWS.items() if row["needs"] != "linear"
]


@pytest.mark.parametrize(("name", "model_kind"), CASES)
def test_run_equals_the_steps_for_every_estimator(name, model_kind):
    build, us, ys = _case(ROWS[name], model_kind)
    whole, stepped = build(), build()
    log = whole.run(us, ys)
    assert len(log) == len(us) and log.kind == whole.kind
    for k in range(len(us)):
        e = stepped.step(us[k], ys[k])
        np.testing.assert_array_equal(log.center[k], e.center, err_msg=f"centre at row {k}")
        if e.lower is None:
            assert e.kind == "point"
            assert np.all(np.isnan(log.lower[k])) and np.all(np.isnan(log.upper[k])) and np.isnan(log.trace[k])
        else:
            np.testing.assert_array_equal(log.lower[k], e.lower)
            np.testing.assert_array_equal(log.upper[k], e.upper)
            np.testing.assert_allclose(log.trace[k], np.trace(e.shape), rtol=1e-14)
        assert log.status[k] == e.status
        assert bool(log.clean[k]) == e.clean
        for key, value in e.details.items():
            np.testing.assert_array_equal(log.details[key][k], np.nan if value is None else value)
    np.testing.assert_array_equal(whole.x, stepped.x)
    np.testing.assert_array_equal(whole.P, stepped.P)


def test_consecutive_runs_equal_one_run():
    build, us, ys = _case(ROWS["smf"], "linear", steps=100)
    one, pieces = build(), build()
    whole = one.run(us, ys)
    first, second = pieces.run(us[:37], ys[:37]), pieces.run(us[37:], ys[37:])
    np.testing.assert_array_equal(whole.center, np.vstack([first.center, second.center]))
    np.testing.assert_array_equal(whole.upper, np.vstack([first.upper, second.upper]))
    assert whole.status == first.status + second.status


def test_results_are_read_only_arrays_of_the_documented_shapes():
    build, us, ys = _case(ROWS["kf"], "linear", steps=10)
    log = build().run(us, ys)
    assert log.center.shape == log.lower.shape == log.upper.shape == (10, 3)
    assert log.trace.shape == log.clean.shape == (10,) and log.clean.dtype == bool
    with pytest.raises(ValueError):
        log.center[0, 0] = 1.0
    est = build()
    with pytest.raises(ValueError):
        est.x[0] = 1.0


def test_a_model_without_input_runs_without_us():
    a = np.array([[0.9, 0.1], [0.0, 0.8]])
    model = pe.Model(a, np.zeros((2, 0)), [[1.0, 0.0]])
    kf = pe.KalmanFilter(model, Q=1e-3, R=1e-2)
    ys = np.linspace(0, 1, 20).reshape(-1, 1)
    log = kf.run(None, ys)
    again = pe.KalmanFilter(model, Q=1e-3, R=1e-2)
    for y in ys:
        e = again.step(None, y)
    np.testing.assert_array_equal(log.center[-1], e.center)


def test_a_log_beyond_the_memory_limit_is_refused_before_anything_runs():
    n = 64
    model = pe.Model(np.eye(n) * 0.5, np.zeros((n, 0)), np.ones((1, n)))
    kf = pe.KalmanFilter(model)
    rows = pe.MAX_RUN_VALUES // n + 1
    ys = np.broadcast_to(np.zeros(1), (rows, 1))  # no memory of its own
    with pytest.raises(ValueError, match="MAX_RUN_VALUES"):
        kf.run(None, ys)
    assert kf.estimate.status == "initial"


def test_the_gil_is_released_during_a_run():
    """While one thread is inside a long run, another thread's Python code keeps running (if the
    run held the GIL, the main thread could not come back from its short sleep before the run
    ended)."""
    import threading
    import time

    build, us, ys = _case(ROWS["smf"], "linear", steps=30_000)
    est = build()
    started = threading.Event()

    def work():
        started.set()
        est.run(us, ys)

    t = threading.Thread(target=work)
    t.start()
    started.wait()
    time.sleep(0.005)
    alive_while_main_runs = t.is_alive()
    t.join()
    assert alive_while_main_runs
