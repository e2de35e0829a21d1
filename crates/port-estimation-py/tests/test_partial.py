"""Partial measurements: a GNSS at 1 Hz beside a 10 Hz yaw-rate gyro (or speed sensor), with two
GNSS dropouts of 30 s. Each step updates with the measured outputs only; the references are filterpy
runs that set ``H`` (``hx``) and ``R`` to the measured subset at each step and skip the update when
nothing was measured: the Kalman filter to 1e-10, the EKF to 1e-9, the UKF to 1e-6.
"""

from __future__ import annotations

import pickle

import numpy as np
import pytest
from conftest import assert_close
from filterpy.kalman import ExtendedKalmanFilter as FilterpyEKF
from filterpy.kalman import KalmanFilter as FilterpyKF
from filterpy.kalman import MerweScaledSigmaPoints
from filterpy.kalman import UnscentedKalmanFilter as FilterpyUKF

import port_estimation as pe

BICYCLE = """
[model]
states = ["x", "y", "psi", "v"]
inputs = ["a", "delta"]
outputs = ["gnss_x", "gnss_y", "gyro"]
angles = ["psi"]
ts = 0.1
discretization = "rk4"

[parameters]
lf = 1.5
lr = 2.0

[definitions]
beta = "atan(lr / (lf + lr) * tan(delta))"

[dxdt]
x = "v * cos(psi + beta)"
y = "v * sin(psi + beta)"
psi = "v / lr * sin(beta)"
v = "a"

[h]
gnss_x = "x"
gnss_y = "y"
gyro = "v / lr * sin(beta)"
"""

STEPS = 1200
DROPOUTS = [(300, 600), (800, 1100)]  # rows without GNSS: 30 s each at 10 Hz


def _mask(k, m_gnss=2, m_fast=1):
    gnss = k % 10 == 0 and not any(a <= k < b for a, b in DROPOUTS)
    return np.array([gnss] * m_gnss + [True] * m_fast)


def _bicycle_log(seed=4):
    model = pe.Model.from_equations(BICYCLE, "bicycle.toml")
    rng = np.random.default_rng(seed)
    x = np.array([0.0, 0.0, 0.2, 5.0])
    us, ys, masks = np.zeros((STEPS, 2)), np.zeros((STEPS, 3)), np.zeros((STEPS, 3), dtype=bool)
    for k in range(STEPS):
        us[k] = [0.3 * np.sin(k / 50), 0.15 * np.sin(k / 80)]
        x = model.f(x, us[k]) + rng.normal(scale=[0.01, 0.01, 0.002, 0.02])
        ys[k] = model.h(x, us[k]) + rng.normal(scale=[0.5, 0.5, 0.01])
        masks[k] = _mask(k)
        ys[k][~masks[k]] = np.nan
    return model, us, ys, masks


Q_BIKE = np.diag([1e-4, 1e-4, 4e-6, 4e-4])
R_BIKE = np.diag([0.25, 0.25, 1e-4])
X0_BIKE, P0_BIKE = np.array([0.5, -0.5, 0.15, 4.5]), np.diag([1.0, 1.0, 0.04, 1.0])


def test_the_log_is_multi_rate_with_dropouts():
    _, _, _, masks = _bicycle_log()
    assert masks[:, 2].all() and 0 < masks[:, 0].sum() < STEPS // 10
    assert not masks[300:600, 0].any() and not masks[800:1100, 0].any()


def test_kalman_filter_equals_filterpy_with_the_measured_rows():
    # Constant velocity in the plane: GNSS position at 1 Hz, wheel-speed velocity at 10 Hz.
    dt = 0.1
    a = np.block([[np.eye(2), dt * np.eye(2)], [np.zeros((2, 2)), np.eye(2)]])
    b, c = np.zeros((4, 0)), np.eye(4)
    q, r = np.diag([1e-4, 1e-4, 1e-2, 1e-2]), np.diag([0.25, 0.25, 0.01, 0.01])
    rng = np.random.default_rng(5)
    x, x0, p0 = np.array([0.0, 0.0, 3.0, 1.0]), np.array([0.3, -0.2, 2.8, 1.1]), np.eye(4)
    ours = pe.KalmanFilter(pe.Model(a, b, c), x0=x0, P0=p0, Q=q, R=r)
    ref = FilterpyKF(dim_x=4, dim_z=4)
    ref.x, ref.P, ref.F, ref.Q = x0.copy(), p0.copy(), a, q
    for k in range(STEPS):
        x = a @ x + rng.multivariate_normal(np.zeros(4), q)
        y = c @ x + rng.multivariate_normal(np.zeros(4), r)
        mask = _mask(k, m_gnss=2, m_fast=2)
        e = ours.step(None, np.ma.masked_array(y, mask=~mask))
        ref.predict()
        ref.update(y[mask], R=r[np.ix_(mask, mask)], H=c[mask])
        assert_close(e.center, ref.x, rtol=1e-10, what=f"x at step {k}")
        assert_close(e.shape, ref.P, rtol=1e-10, what=f"P at step {k}")


def test_ekf_equals_filterpy_with_the_measured_rows():
    model, us, ys, masks = _bicycle_log()
    ours = pe.ExtendedKalmanFilter(model, x0=X0_BIKE, P0=P0_BIKE, Q=Q_BIKE, R=R_BIKE)
    ref = FilterpyEKF(dim_x=4, dim_z=3, dim_u=2)
    ref.x, ref.P, ref.Q = X0_BIKE.copy(), P0_BIKE.copy(), Q_BIKE
    for k, (u, y, mask) in enumerate(zip(us, ys, masks)):
        e = ours.step(u, y, measured=mask)
        ref.F = model.F(ref.x, u)
        ref.P = ref.F @ ref.P @ ref.F.T + ref.Q
        ref.x = model.f(ref.x, u)
        if mask.any():
            ref.update(
                y[mask],
                HJacobian=lambda x, u=u, mask=mask: model.H(x, u)[mask],
                Hx=lambda x, u=u, mask=mask: model.h(x, u)[mask],
                R=R_BIKE[np.ix_(mask, mask)],
            )
            assert e.status == "converged"
        else:
            assert e.status == "predicted"
        assert_close(e.center, ref.x, rtol=1e-9, what=f"x at step {k}")
        assert_close(e.shape, ref.P, rtol=1e-9, what=f"P at step {k}")


def test_ukf_equals_filterpy_with_the_measured_rows():
    model, us, ys, masks = _bicycle_log()
    ours = pe.UnscentedKalmanFilter(model, x0=X0_BIKE, P0=P0_BIKE, Q=Q_BIKE, R=R_BIKE, alpha=0.5, beta=2.0, kappa=0.0)
    points = MerweScaledSigmaPoints(4, alpha=0.5, beta=2.0, kappa=0.0)
    ref = FilterpyUKF(dim_x=4, dim_z=3, dt=None, fx=lambda x, dt, u: model.f(x, u), hx=None, points=points)
    ref.x, ref.P, ref.Q = X0_BIKE.copy(), P0_BIKE.copy(), Q_BIKE
    for k, (u, y, mask) in enumerate(zip(us, ys, masks)):
        e = ours.step(u, np.ma.masked_invalid(y))
        ref.predict(u=u)
        if mask.any():
            ref.update(y[mask], R=R_BIKE[np.ix_(mask, mask)], hx=lambda x, u=u, mask=mask: model.h(x, u)[mask])
        assert_close(e.center, ref.x, rtol=1e-6, what=f"x at step {k}")
        assert_close(e.shape, ref.P, rtol=1e-6, what=f"P at step {k}")


def test_the_certified_filter_contains_the_truth_through_the_dropouts():
    model = pe.Model.from_equations(BICYCLE, "bicycle.toml")
    rng = np.random.default_rng(6)
    w, v = np.array([0.01, 0.01, 0.002, 0.02]), np.array([0.5, 0.5, 0.01])
    x = np.array([0.0, 0.0, 0.2, 5.0])
    czf = pe.Estimator("czf-nl", model, x0=x + [0.5, -0.5, 0.05, 0.3], P0=np.diag([1.0, 1.0, 0.1, 0.5]), Q=w, R=v)
    widths = []
    for k in range(STEPS):
        u = np.array([0.3 * np.sin(k / 50), 0.15 * np.sin(k / 80)])
        x = model.f(x, u) + w * rng.choice([-1.0, 1.0], size=4)
        y = model.h(x, u) + v * rng.choice([-1.0, 1.0], size=3)
        e = czf.step(u, y, measured=_mask(k))
        assert np.all(e.lower <= x) and np.all(x <= e.upper), f"step {k}: {x} outside [{e.lower}, {e.upper}]"
        widths.append(e.upper[0] - e.lower[0])
    # The position's width grows through a dropout and shrinks when the GNSS returns.
    assert widths[599] > 2 * widths[299] and widths[700] < widths[599] / 2


def test_the_fuzzy_adaptive_filter_takes_a_partial_fix_that_defines_its_scale():
    # Its noise scale comes from the receiver status and the horizontal innovation: a partial fix
    # with both (the third output missing) is the Kalman partial step with t_k R; one without a
    # horizontal output is refused by name, unchanged; nothing measured predicts.
    a, b, c = np.eye(3), np.zeros((3, 0)), np.eye(3)
    est = pe.Estimator("fkf", pe.Model(a, b, c), x0=np.zeros(3), P0=1.0, Q=1e-2, R=1e-2)
    with pytest.raises(pe.EstimationError, match="fkf.*partial"):
        est.step(None, np.array([0.1, np.nan, 0.2, 8.0, 3.0]), measured=np.array([True, False, True, True, True]))
    assert_close(est.x, np.zeros(3))
    assert est.step(None, np.zeros(5), measured=np.array([False] * 5)).status.startswith("predicted")
    e = est.step(None, np.array([0.1, -0.1, np.nan, 8.0, 3.0]), measured=np.array([True, True, False, True, True]))
    assert est.x[0] > 0.0 and est.x[1] < 0.0 and est.x[2] == 0.0
    assert e.details["scale"] > 0.0
    est.step(None, np.array([0.0, 0.0, 0.0, 8.0, 3.0]), measured=np.array([True] * 5))


@pytest.mark.parametrize("name", ["rmhe", "mhe"])
def test_the_linear_moving_horizon_estimators_drop_the_unmeasured_rows(name):
    # R is diagonal: a partial sample is the sample of a model whose unmeasured rows are zero (a
    # value never read), the same numbers.
    a, b = np.array([[1.0, 0.1], [0.0, 0.9]]), np.zeros((2, 0))
    box = {"w_lower": [-0.1] * 2, "w_upper": [0.1] * 2, "v_lower": [-0.5] * 2, "v_upper": [0.5] * 2}
    kw = {"x0": np.zeros(2), "P0": 1.0, "Q": 1e-2, "R": [1e-2, 2e-2], "horizon": 4, **box}
    ours = pe.Estimator(name, pe.Model(a, b, np.eye(2)), **kw)
    blind = pe.Estimator(name, pe.Model(a, b, np.array([[1.0, 0.0], [0.0, 0.0]])), **kw)
    rng = np.random.default_rng(2)
    for _ in range(12):
        y = rng.normal(scale=0.1, size=2)
        e = ours.step(None, np.array([y[0], np.nan]), measured=np.array([True, False]))
        np.testing.assert_array_equal(e.center, blind.step(None, np.array([y[0], 0.0])).center)


def test_bad_masks_are_refused():
    kf = pe.KalmanFilter(pe.Model(np.eye(2), np.zeros((2, 0)), np.eye(2)), x0=np.zeros(2), P0=1.0, Q=1e-2, R=1e-2)
    with pytest.raises(ValueError, match="2 entries"):
        kf.step(None, np.zeros(2), measured=np.array([True]))
    with pytest.raises(ValueError, match="booleans"):
        kf.step(None, np.zeros(2), measured=np.array([1, 0]))
    with pytest.raises(ValueError, match="not both"):
        kf.step(None, np.ma.masked_array(np.zeros(2), mask=[False, True]), measured=np.array([True, False]))
    with pytest.raises(ValueError, match="non-finite measured entry"):
        kf.step(None, np.array([np.nan, 0.0]), measured=np.array([True, False]))
    with pytest.raises(ValueError, match="non-finite"):
        kf.step(None, np.array([np.nan, 0.0]))
    assert_close(kf.x, np.zeros(2))


def test_run_takes_masked_logs_and_equals_the_partial_steps():
    model, us, ys, masks = _bicycle_log()
    steps = pe.ExtendedKalmanFilter(model, x0=X0_BIKE, P0=P0_BIKE, Q=Q_BIKE, R=R_BIKE)
    want = np.array([steps.step(u, y, measured=m).center for u, y, m in zip(us, ys, masks)])
    for kwargs in ({"ys": np.ma.masked_invalid(ys)}, {"ys": ys, "measured": masks}):
        est = pe.ExtendedKalmanFilter(model, x0=X0_BIKE, P0=P0_BIKE, Q=Q_BIKE, R=R_BIKE)
        run = est.run(us, **kwargs)
        np.testing.assert_array_equal(run.center, want)
        assert run.status[1].startswith("predicted") or masks[1].any()
        # The result says which outputs each step used, and keeps it through pickling.
        np.testing.assert_array_equal(run.measured, masks)
        np.testing.assert_array_equal(pickle.loads(pickle.dumps(run)).measured, masks)
    plain = pe.KalmanFilter(pe.Model(np.eye(2), np.zeros((2, 0)), np.eye(2)), x0=np.zeros(2), P0=1.0, Q=1e-2, R=1e-2)
    assert plain.run(None, np.zeros((3, 2))).measured is None
    with pytest.raises(ValueError, match="shape of ys"):
        pe.ExtendedKalmanFilter(model, x0=X0_BIKE, P0=P0_BIKE, Q=Q_BIKE, R=R_BIKE).run(us, ys, measured=masks[:, :2])
    with pytest.raises(ValueError, match=r"ys\[1, 0\] is not finite"):
        pe.ExtendedKalmanFilter(model, x0=X0_BIKE, P0=P0_BIKE, Q=Q_BIKE, R=R_BIKE).run(us, ys)


def test_the_fleet_reads_null_measurements_as_partial_rows(tmp_path):
    pa = pytest.importorskip("pyarrow")
    pq = pytest.importorskip("pyarrow.parquet")
    from port_estimation import fleet

    model, us, ys, masks = _bicycle_log()
    k = np.arange(STEPS)
    names = fleet.log_columns(2, 3)
    columns = [pa.array(k)] + [pa.array(c) for c in us.T]
    columns += [pa.array(np.where(m, c, 0.0), mask=~m) for c, m in zip(ys.T, masks.T)]
    path = tmp_path / "log.parquet"
    pq.write_table(pa.Table.from_arrays(columns, names=names), path)
    _, _, read = fleet.read_log(path, inputs=2, measurements=3)
    assert isinstance(read, np.ma.MaskedArray)
    np.testing.assert_array_equal(~np.ma.getmaskarray(read), masks)
    est = pe.ExtendedKalmanFilter(model, x0=X0_BIKE, P0=P0_BIKE, Q=Q_BIKE, R=R_BIKE)
    want = est.run(us, ys, measured=masks).center
    est = pe.ExtendedKalmanFilter(model, x0=X0_BIKE, P0=P0_BIKE, Q=Q_BIKE, R=R_BIKE)
    np.testing.assert_array_equal(est.run(us, read).center, want)


@pytest.mark.parametrize("name", ["smf", "yang-li-with-input", "smf-nl"])
def test_ellipsoid_filters_step_with_the_projection_of_their_noise_ellipsoid(name):
    # The filter of the model whose outputs are the measured ones, with the sub-block of R: the
    # same numbers (bit for bit for the linear filters), through Python's masks.
    a = np.array([[1.0, 0.1, 0.0], [0.0, 1.0, 0.1], [0.0, 0.0, 0.95]])
    b = np.array([[0.0], [0.05], [0.1]])
    c = np.array([[1.0, 0.0, 0.0], [0.5, 1.0, 0.0], [0.0, 0.2, 1.0]])
    r = np.array([[0.05, 0.01, 0.02], [0.01, 0.04, -0.01], [0.02, -0.01, 0.09]])
    keep = [0, 2]
    ours = pe.Estimator(name, pe.Model(a, b, c), x0=np.zeros(3), P0=1.0, Q=1e-3, R=r)
    reduced = pe.Estimator(name, pe.Model(a, b, c[keep]), x0=np.zeros(3), P0=1.0, Q=1e-3, R=r[np.ix_(keep, keep)])
    rng = np.random.default_rng(5)
    for k in range(30):
        u = np.array([np.sin(0.3 * k)])
        y = rng.normal(scale=0.1, size=3)
        e = ours.step(u, np.ma.masked_array(y, mask=[False, True, False]))
        want = reduced.step(u, y[keep])
        if name == "smf-nl":
            assert_close(e.center, want.center, rtol=1e-9)
        else:
            np.testing.assert_array_equal(e.center, want.center)
            np.testing.assert_array_equal(e.shape, want.shape)
