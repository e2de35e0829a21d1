"""The set-membership filters contain the true state when every noise sits on the boundary of its
set (the hardest case the bounds allow), and never flag such data as inconsistent."""

from __future__ import annotations

import numpy as np
import pytest
from conftest import on_boundary, random_system

import port_estimation as pe


def _boundary_run(rng, a, b, c, q, r, p0, x0_center, steps, u_scale=1.0):
    n, p = b.shape
    x = x0_center + on_boundary(rng, p0)
    us = rng.uniform(-u_scale, u_scale, size=(steps, p))
    xs, ys = np.zeros((steps, n)), np.zeros((steps, c.shape[0]))
    for k in range(steps):
        x = a @ x + b @ us[k] + on_boundary(rng, q)
        xs[k] = x
        ys[k] = c @ x + on_boundary(rng, r)
    return us, ys, xs


def _contained(center, shape, x):
    d = x - center
    return float(d @ np.linalg.solve(shape, d))


CASES = [
    ("smf", {}),
    ("smf", {"solver": "faer-ipm"}),
    ("yang-li-with-input", {}),
    ("yang-li", {"u_lower": [-1.0, -1.0], "u_upper": [1.0, 1.0]}),
]


@pytest.mark.parametrize(("name", "settings"), CASES)
@pytest.mark.parametrize("seed", range(3))
def test_the_set_holds_the_state_with_noise_on_the_boundary(name, settings, seed):
    rng = np.random.default_rng(100 + seed)
    a, b, c, q, r, p0 = random_system(rng, 4, 2, 3)
    x0 = rng.normal(size=4)
    steps = 60 if settings.get("solver") else 300
    us, ys, xs = _boundary_run(rng, a, b, c, q, r, p0, x0, steps)
    est = pe.Estimator(name, pe.Model(a, b, c), x0=x0, P0=p0, Q=q, R=r, **settings)
    log = est.run(us, ys)
    assert log.kind == "guaranteed ellipsoid"
    assert all(log.clean), set(log.status)
    assert np.all(log.lower <= xs) and np.all(xs <= log.upper), "a guaranteed interval missed the state"
    # The ellipsoid itself, step by step (the run's last set, and a second filter's every set).
    again = pe.Estimator(name, pe.Model(a, b, c), x0=x0, P0=p0, Q=q, R=r, **settings)
    for k in range(steps):
        e = again.step(us[k], ys[k])
        assert e.guaranteed
        assert _contained(e.center, e.shape, xs[k]) <= 1.0 + 1e-9, f"step {k}: the state left the set"
    assert _contained(est.x, est.P, xs[-1]) <= 1.0 + 1e-9


def test_the_interval_observer_narrows_the_published_interval_and_leaves_the_set():
    # A drifting second state dominates the ellipsoid's trace; the first is measured to ±0.1. With
    # the observer (the default) the first state's interval is y ± 0.1 at most, inside the plain
    # filter's, holding the truth; the ellipsoid is the same bit for bit.
    rng = np.random.default_rng(7)
    a, b, c = np.array([[1.0, 0.1], [0.0, 1.0]]), np.zeros((2, 1)), np.array([[1.0, 0.0]])
    q, r, p0 = np.diag([1e-4, 1.0]), np.array([[0.01]]), 4.0 * np.eye(2)
    us, ys, xs = _boundary_run(rng, a, b, c, q, r, p0, np.zeros(2), 200)
    kw = dict(x0=np.zeros(2), P0=p0, Q=q, R=r)
    filters = [pe.Estimator("smf", pe.Model(a, b, c), **kw), pe.SetMembershipFilter(pe.Model(a, b, c), **kw)]
    plain_filter = pe.Estimator("smf", pe.Model(a, b, c), interval_observer=False, **kw)
    observed, same = (f.run(us, ys) for f in filters)
    plain = plain_filter.run(us, ys)
    assert np.array_equal(observed.center, plain.center) and np.array_equal(filters[0].P, plain_filter.P)
    assert np.array_equal(same.lower, observed.lower) and np.array_equal(same.upper, observed.upper)
    assert np.all(observed.lower <= xs) and np.all(xs <= observed.upper)
    assert np.all(plain.lower <= observed.lower) and np.all(observed.upper <= plain.upper)
    width = observed.upper[:, 0] - observed.lower[:, 0]
    assert np.all(width <= 0.2 + 1e-12)
    assert np.median(plain.upper[:, 0] - plain.lower[:, 0]) > 0.3


def test_the_carrier_set_holds_the_state():
    """The straddle carrier of the paper, at 1 ms, steering inputs of a few degrees."""
    rng = np.random.default_rng(3)
    model = pe.Model.carrier(speed=6.0, load=1)
    a, b, c = model.A, model.B, model.C
    q, r, p0 = np.eye(4) * 1e-8, np.eye(4) * 1e-6, np.eye(4) * 1e-2
    us, ys, xs = _boundary_run(rng, a, b, c, q, r, p0, np.zeros(4), 500, u_scale=0.05)
    smf = pe.SetMembershipFilter(model, P0=p0, Q=q, R=r)
    log = smf.run(us, ys)
    # (The first step, from a set 10^4 times wider than the measurement bound, may publish the
    # certified fallback: still guaranteed.)
    assert not any("inconsistent" in s or "not-guaranteed" in s for s in log.status), set(log.status)
    assert np.all(log.lower <= xs) and np.all(xs <= log.upper)
    assert set(log.details) == {"tau1", "tau2", "tau3", "iterations"}
    assert np.all(np.isfinite(log.details["tau1"]))


def test_a_prediction_alone_grows_the_set_and_keeps_the_state():
    rng = np.random.default_rng(5)
    a, b, c, q, r, p0 = random_system(rng, 3, 1, 2)
    us, ys, xs = _boundary_run(rng, a, b, c, q, r, p0, np.zeros(3), 20)
    smf = pe.SetMembershipFilter(pe.Model(a, b, c), P0=p0, Q=q, R=r)
    for k in range(10):
        smf.step(us[k], ys[k])
    before = np.trace(smf.P)
    e = smf.predict(us[10])
    assert e.status == "predicted" and e.guaranteed
    assert np.trace(e.shape) > before
    assert _contained(e.center, e.shape, xs[10]) <= 1.0 + 1e-9
    # The update after it is the joint step: the same numbers as one step.
    joint = pe.SetMembershipFilter(pe.Model(a, b, c), P0=p0, Q=q, R=r)
    for k in range(11):
        last = joint.step(us[k], ys[k])
    e = smf.update(ys[10])
    np.testing.assert_array_equal(e.center, last.center)
    np.testing.assert_array_equal(e.shape, last.shape)


def test_the_nonlinear_filter_holds_the_vessels_state_with_noise_on_the_boundary():
    # smf-nl on the compiled vessel (Euler, enclosures of its Hessians): the truth stays inside.
    vessel = pe.Model.vessel()
    assert vessel.capability == "second-order"
    rng = np.random.default_rng(5)
    q = np.diag([1e-2, 1e-2, 1e-4, 1e-4, 1e-4, 1e-6])
    r = np.diag([1.0, 1.0, 1e-2])
    p0 = np.diag([4.0, 4.0, 0.01, 0.01, 0.01, 1e-4])
    est = pe.Estimator("smf-nl", vessel, x0=np.zeros(6), P0=p0, Q=q, R=r)
    x = on_boundary(rng, p0)
    for k in range(200):
        u = np.array([2e5, 5e4, 1e6]) * np.sin(0.1 * k / np.array([5.0, 6.0, 7.0]))
        x = vessel.f(x, u) + on_boundary(rng, q)
        y = vessel.h(x, u) + on_boundary(rng, r)
        e = est.step(u, y)
        assert e.kind == "guaranteed ellipsoid"
        assert _contained(e.center, e.shape, x) <= 1.0, k
    # A linear model is the linear filter's (to rounding).
    lin = pe.Model(np.array([[1.0, 0.1], [0.0, 0.9]]), np.array([[0.0], [0.1]]), np.array([[1.0, 0.0]]))
    kw = dict(x0=np.zeros(2), P0=np.eye(2), Q=np.eye(2) * 0.01, R=np.eye(1) * 0.1)
    us, ys = np.ones((30, 1)), np.linspace(0, 1, 30)[:, None]
    a = pe.Estimator("smf", lin, **kw).run(us, ys).center
    b = pe.Estimator("smf-nl", lin, **kw).run(us, ys).center
    np.testing.assert_allclose(a, b, rtol=1e-12, atol=1e-12)


def test_declared_speed_limits_keep_the_vessels_set_from_growing():
    # At an oblique heading, without bounds on the (unmeasured) velocities, the remainder of the
    # kinematics feeds the set's growth (docs/nonlinear-smf.md, "The vessel"); x_lower/x_upper
    # declare the speed limits (N1'). Both filters on the same data, noise on the boundary.
    vessel = pe.Model.vessel()
    rng = np.random.default_rng(8)
    q = np.diag([1e-2, 1e-2, 1e-4, 1e-4, 1e-4, 1e-6])
    r = np.diag([1.0, 1.0, 1e-2])
    p0 = np.diag([4.0, 4.0, 0.01, 0.01, 0.01, 1e-4])
    x0 = np.array([0.0, 0.0, np.pi / 4, 0.0, 0.0, 0.0])
    inf = np.inf
    kw = dict(x0=x0, P0=p0, Q=q, R=r)
    lo, hi = [-inf, -inf, -inf, -2.0, -2.0, -0.1], [inf, inf, inf, 2.0, 2.0, 0.1]
    bounded = pe.Estimator("smf-nl", vessel, x_lower=lo, x_upper=hi, **kw)
    free = pe.Estimator("smf-nl", vessel, **kw)
    x = x0 + on_boundary(rng, p0)
    for k in range(300):
        u = np.array([2e5, 5e4, 1e6]) * np.sin(0.1 * k / np.array([5.0, 6.0, 7.0]))
        x = vessel.f(x, u) + on_boundary(rng, q)
        y = vessel.h(x, u) + on_boundary(rng, r)
        assert np.all(np.abs(x[3:]) <= [2.0, 2.0, 0.1])
        for est in (bounded, free):
            e = est.step(u, y)
            assert _contained(e.center, e.shape, x) <= 1.0, k
    wb, wf = 2 * np.sqrt(bounded.P[0, 0]), 2 * np.sqrt(free.P[0, 0])
    assert wb < 5.0 and wf > 3 * wb, (wb, wf)
    # The linear filter cuts its published interval by them through its interval observer (and
    # refuses them with the observer off); a set outside them is inconsistent data, named with its
    # step and state.
    lin = pe.Model(np.array([[1.0, 0.1], [0.0, 0.9]]), np.array([[0.0], [0.1]]), np.array([[1.0, 0.0]]))
    small = dict(x0=np.zeros(2), P0=np.eye(2), Q=np.eye(2) * 0.01, R=np.eye(1) * 0.1)
    cut = pe.SetMembershipFilter(lin, x_lower=[-0.5, -inf], x_upper=[0.25, inf], **small)
    assert cut.estimate.lower[0] == -0.5 and cut.estimate.upper[0] == 0.25
    assert cut.estimate.lower[1] == pytest.approx(-1.0)
    with pytest.raises(ValueError, match="interval observer, which is off"):
        pe.Estimator("smf", lin, x_lower=[-1, -1], x_upper=[1, 1], interval_observer=False, **small)
    with pytest.raises(ValueError, match="cannot be turned off"):
        pe.Estimator("smf-nl", lin, interval_observer=False, **small)
    with pytest.raises(ValueError, match="interval_observer must be True or False"):
        pe.Estimator("smf", lin, interval_observer="yes", **small)
    est = pe.Estimator("smf-nl", lin, x_lower=[-inf, 5.0], x_upper=[inf, 6.0], **small)
    with pytest.raises(pe.InconsistentDataError) as info:
        est.step([0.0], [0.0])
    assert info.value.step == 1 and info.value.state == 1
    assert info.value.kind == "inconsistent-data"


UNDEFINED_AT_THE_CENTRE = """
[model]
states = ["x", "tq"]
inputs = ["u"]
outputs = ["y"]

[f]
x = "x + 0 * ln(tq + 1)"
tq = "tq + u"

[h]
y = "x"
"""


@pytest.mark.parametrize("name", ["smf-nl", "czf-nl"])
def test_a_function_undefined_at_the_centre_loses_the_guarantee_and_changes_nothing(name):
    # The interval enclosure of 0 * ln(tq + 1) at tq = -2 is 0; its value is NaN: the EKF refuses
    # the step, and the certified filters must not publish a converged set.
    model = pe.Model.from_equations(UNDEFINED_AT_THE_CENTRE, "undefined.toml")
    est = pe.Estimator(name, model, x0=[0.0, -2.0], P0=1e-4 * np.eye(2), Q=1e-6 * np.eye(2), R=1e-2 * np.eye(1))
    before = (est.x.copy(), est.P.copy(), est.estimate.status)
    with pytest.raises(pe.EstimationError, match=r"guarantee.*f.* undefined at the set's centre.*NaN") as info:
        est.step([0.0], [0.0])
    assert not isinstance(info.value, ValueError)
    np.testing.assert_array_equal(est.x, before[0])
    np.testing.assert_array_equal(est.P, before[1])
    assert est.estimate.status == before[2]
    # Defined there (tq = 0), the same filter steps.
    ok = pe.Estimator(name, model, x0=[0.0, 0.0], P0=1e-4 * np.eye(2), Q=1e-6 * np.eye(2), R=1e-2 * np.eye(1))
    assert ok.step([0.0], [0.0]).guaranteed
