"""Angles declared once: a yard tractor circling between two landmarks, so that both measured
bearings cross ±π every turn (examples/range-bearing, ``angles = ["psi", "bearing_1", "bearing_2"]``).

References: an EKF written here in numpy with the bearings' residuals wrapped (1e-8 over the whole
log, crossings included), filterpy's UnscentedKalmanFilter with wrapped ``residual_x``/``residual_z``
and the circular means of ``crates/estimators/src/ukf.rs`` as ``x_mean_fn``/``z_mean_fn`` (1e-6), a
numpy Kalman filter with a wrapped compass innovation.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from conftest import assert_close
from filterpy.kalman import MerweScaledSigmaPoints
from filterpy.kalman import UnscentedKalmanFilter as FilterpyUKF

import port_estimation as pe

ROOT = Path(__file__).resolve().parents[3]
BEARINGS = [1, 3]


def wrap(a):
    return (np.asarray(a) + np.pi) % (2 * np.pi) - np.pi


FORMS = ["as written", "wrapped"]


def _read(form, tmp_path):
    """The tractor's model file; ``wrapped``: its bearings written as ``atan2(sin b, cos b)``, so that
    ``h`` itself jumps at ±π and the UKF's sigma points straddle it (its circular means at work)."""
    path = ROOT / "examples" / "range-bearing" / "model.toml"
    if form == "as written":
        return pe.read_model(path)
    text = path.read_text()
    for i, (lx, ly) in [(1, ("l1x", "l1y")), (2, ("l2x", "l2y"))]:
        b = f"atan2({ly} - y, {lx} - x) - psi"
        assert b in text
        text = text.replace(f'bearing_{i} = "{b}"', f'bearing_{i} = "atan2(sin({b}), cos({b}))"')
    out = tmp_path / "wrapped.toml"
    out.write_text(text)
    return pe.read_model(out)


def _circling(form="as written", tmp_path=None, steps=600, seed=3):
    mf = _read(form, tmp_path)
    model = mf.model
    rng = np.random.default_rng(seed)
    x = np.array([1.5, -1.5, 0.15, 1.3])
    us, ys, xs = np.zeros((steps, 2)), np.zeros((steps, 4)), np.zeros((steps, 4))
    for k in range(steps):
        us[k] = [0.5 * (3.0 - x[3]), 0.4]
        x = model.f(x, us[k]) + rng.normal(scale=[0.01, 0.01, 0.002, 0.02])
        y = model.h(x, us[k]) + rng.normal(scale=[0.3, 0.005, 0.3, 0.005])
        y[BEARINGS] = wrap(y[BEARINGS])
        xs[k], ys[k] = x, y
    crossings = int((np.abs(np.diff(ys[:, BEARINGS], axis=0)) > np.pi).sum())
    assert crossings >= 4, crossings
    return mf, model, us, ys, xs


def test_the_model_file_declares_its_angles():
    mf = pe.read_model(ROOT / "examples" / "range-bearing" / "model.toml")
    assert mf.model.angles == {"states": [2], "outputs": [1, 3]}
    assert pe.Model.vessel().angles == {"states": [2], "outputs": [2]}
    assert pe.Model.truck().angles == {"states": [], "outputs": []}


@pytest.mark.parametrize("form", FORMS)
def test_ekf_equals_a_numpy_ekf_with_wrapped_residuals_across_the_crossings(form, tmp_path):
    mf, model, us, ys, _ = _circling(form, tmp_path)
    q, r = mf.Q, mf.R
    ours = pe.ExtendedKalmanFilter(model, x0=mf.x0, P0=mf.P0, Q=q, R=r)
    x, p = mf.x0.copy(), mf.P0.copy()
    for k, (u, y) in enumerate(zip(us, ys)):
        e = ours.step(u, y)
        f = model.F(x, u)
        x = model.f(x, u)
        p = f @ p @ f.T + q
        h = model.H(x, u)
        res = y - model.h(x, u)
        res[BEARINGS] = wrap(res[BEARINGS])
        s = h @ p @ h.T + r
        gain = np.linalg.solve(s, h @ p).T
        x = x + gain @ res
        ikh = np.eye(4) - gain @ h
        p = ikh @ p @ ikh.T + gain @ r @ gain.T
        assert_close(e.center, x, rtol=1e-8, what=f"x at step {k}")
        assert_close(e.shape, p, rtol=1e-8, what=f"P at step {k}")


def _circular_mean(rows):
    """The UKF's mean of ``crates/estimators/src/ukf.rs``: about the central (first) sigma point."""

    def mean(sigmas, wm):
        out = np.dot(wm, sigmas)
        for i in rows:
            out[i] = sigmas[0, i] + np.dot(wm, wrap(sigmas[:, i] - sigmas[0, i]))
        return out

    return mean


def _wrapped_residual(rows):
    def residual(a, b):
        d = np.subtract(a, b)
        d[rows] = wrap(d[rows])
        return d

    return residual


@pytest.mark.parametrize("form", FORMS)
def test_ukf_equals_filterpy_with_circular_means_across_the_crossings(form, tmp_path):
    mf, model, us, ys, _ = _circling(form, tmp_path)
    q, r = mf.Q, mf.R
    ours = pe.UnscentedKalmanFilter(model, x0=mf.x0, P0=mf.P0, Q=q, R=r, alpha=0.5, beta=2.0, kappa=0.0)
    points = MerweScaledSigmaPoints(4, alpha=0.5, beta=2.0, kappa=0.0)
    ref = FilterpyUKF(
        dim_x=4,
        dim_z=4,
        dt=None,
        fx=lambda x, dt, u: model.f(x, u),
        hx=None,
        points=points,
        x_mean_fn=_circular_mean([2]),
        z_mean_fn=_circular_mean(BEARINGS),
        residual_x=_wrapped_residual([2]),
        residual_z=_wrapped_residual(BEARINGS),
    )
    ref.x, ref.P, ref.Q, ref.R = mf.x0.copy(), mf.P0.copy(), q, r
    for k, (u, y) in enumerate(zip(us, ys)):
        e = ours.step(u, y)
        ref.predict(u=u)
        ref.update(y, hx=lambda x, u=u: model.h(x, u))
        assert_close(e.center, ref.x, rtol=1e-6, what=f"x at step {k}")
        assert_close(e.shape, ref.P, rtol=1e-6, what=f"P at step {k}")


def test_a_linear_compass_is_wrapped_as_declared():
    # Heading and yaw rate, the heading measured by a compass that reports (−π, π].
    a, b, c = np.array([[1.0, 0.1], [0.0, 1.0]]), np.zeros((2, 0)), np.array([[1.0, 0.0]])
    model = pe.Model(a, b, c, angles={"states": [0], "outputs": [0]})
    assert model.angles == {"states": [0], "outputs": [0]}
    q, r = np.diag([1e-6, 1e-4]), np.array([[1e-4]])
    x0, p0 = np.array([3.0, 0.5]), np.eye(2) * 1e-2
    kf = pe.KalmanFilter(model, x0=x0, P0=p0, Q=q, R=r)
    x, p, truth = x0.copy(), p0.copy(), x0.copy()
    for k in range(200):
        truth = a @ truth
        y = wrap(truth[:1])
        e = kf.step(np.zeros(0), y)
        x, p = a @ x, a @ p @ a.T + q
        s = c @ p @ c.T + r
        gain = p @ c.T / s
        x = x + (gain * wrap(y - c @ x)).ravel()
        ikh = np.eye(2) - gain @ c
        p = ikh @ p @ ikh.T + gain @ r @ gain.T
        assert_close(e.center, x, rtol=1e-10, what=f"x at step {k}")
    # The heading went round more than once, and the estimate followed it unwrapped.
    assert kf.x[0] > 3 * np.pi and abs(kf.x[0] - truth[0]) < 1e-2


@pytest.mark.parametrize(
    ("angles", "words"),
    [({"states": [5]}, "states"), ({"outputs": [0, 0]}, "outputs"), ({"heading": [0]}, "heading"), ([0], "dict")],
)
def test_bad_angle_declarations_are_refused(angles, words):
    with pytest.raises(ValueError, match=words):
        pe.Model(np.eye(2), np.zeros((2, 0)), np.eye(2)[:1], angles=angles)


def test_an_unknown_angle_name_in_a_model_file_is_refused_at_its_place(tmp_path):
    text = (ROOT / "examples" / "range-bearing" / "model.toml").read_text()
    bad = text.replace('angles = ["psi", "bearing_1", "bearing_2"]', 'angles = ["psi", "bearing_3"]')
    line = next(i for i, s in enumerate(bad.splitlines(), 1) if s.startswith("angles"))
    path = tmp_path / "rb.toml"
    path.write_text(bad)
    with pytest.raises(ValueError, match=rf"rb\.toml:{line}:\d+.*bearing_3.*neither a state nor an output"):
        pe.read_model(path)


def test_the_linear_set_membership_filter_chooses_the_branch_of_an_angle_output():
    # A heading turning at 0.5 rad/s, measured by a compass across the cut: the filter of the
    # unwrapped measurement, to the rounding of the shift.
    a, c = np.array([[1.0, 0.1], [0.0, 1.0]]), np.eye(2)
    kw = {"x0": np.array([3.0, 0.5]), "P0": np.eye(2) * 0.1, "Q": np.eye(2) * 1e-4, "R": np.diag([0.01, 1e-4])}
    angled = pe.SetMembershipFilter(pe.Model(a, np.zeros((2, 0)), c, angles={"outputs": [0]}), **kw)
    plain = pe.SetMembershipFilter(pe.Model(a, np.zeros((2, 0)), c), **kw)
    theta = 3.0
    for _ in range(40):
        theta += 0.05
        y = np.array([theta, 0.5])
        e = angled.step(np.zeros(0), np.array([np.angle(np.exp(1j * theta)), 0.5]))
        assert_close(e.center, plain.step(np.zeros(0), y).center, rtol=1e-9)
    assert theta > np.pi
