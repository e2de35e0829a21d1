"""Errors: ValueError for bad input, the package's exceptions for what the estimation runs into,
and after any exception the estimator's state is exactly what it was (continuing gives the same
numbers as an estimator that never saw the bad call)."""

from __future__ import annotations

import numpy as np
import pytest
from conftest import random_system

import port_estimation as pe


def _snapshot(est):
    e = est.estimate
    return est.x.copy(), est.P.copy(), e.status, e.details


def _assert_same(est, snap):
    x, p, status, details = snap
    np.testing.assert_array_equal(est.x, x)
    np.testing.assert_array_equal(est.P, p)
    assert est.estimate.status == status
    assert est.estimate.details == details


@pytest.fixture
def system():
    rng = np.random.default_rng(2)
    a, b, c, q, r, p0 = random_system(rng, 3, 1, 2)
    us = rng.uniform(-1, 1, size=(30, 1))
    ys = np.zeros((30, 2))
    x = np.zeros(3)
    for k in range(30):
        x = a @ x + b @ us[k]
        ys[k] = c @ x
    return pe.Model(a, b, c), q, r, p0, us, ys


def test_the_exception_hierarchy():
    assert issubclass(pe.NumericalError, pe.EstimationError)
    assert issubclass(pe.InconsistentDataError, pe.EstimationError)
    assert issubclass(pe.EstimationError, Exception) and not issubclass(pe.EstimationError, ValueError)
    assert pe.InconsistentDataError.__module__ == "port_estimation"


@pytest.mark.parametrize(
    "call",
    [
        lambda e: e.step([np.nan], [0.0, 0.0]),
        lambda e: e.step([0.0], [0.0, np.inf]),
        lambda e: e.step([0.0, 1.0], [0.0, 0.0]),
        lambda e: e.step([0.0], [0.0]),
        lambda e: e.predict([[1.0, 2.0]]),
        lambda e: e.update("not numbers"),
        lambda e: e.step([0.0], [0.0, 0.0], model=pe.Model(np.eye(2), np.zeros((2, 1)), np.eye(2))),
        lambda e: e.run(np.zeros((5, 1)), np.zeros((4, 2))),
        lambda e: e.run(np.zeros((5, 1)), np.zeros((5, 3))),
        lambda e: e.run(np.zeros((5, 1)), np.where(np.arange(10).reshape(5, 2) == 7, np.nan, 0.0)),
    ],
)
@pytest.mark.parametrize("name", ["kf", "smf", "ukf"])
def test_bad_input_is_a_value_error_and_changes_nothing(system, name, call):
    model, q, r, p0, us, ys = system
    est = pe.Estimator(name, model, P0=p0, Q=q, R=r)
    reference = pe.Estimator(name, model, P0=p0, Q=q, R=r)
    for k in range(5):
        est.step(us[k], ys[k])
        reference.step(us[k], ys[k])
    snap = _snapshot(est)
    with pytest.raises(ValueError):
        call(est)
    _assert_same(est, snap)
    for k in range(5, 10):
        np.testing.assert_array_equal(est.step(us[k], ys[k]).center, reference.step(us[k], ys[k]).center)


@pytest.mark.parametrize(
    ("kwargs", "message"),
    [
        ({"P0": -np.eye(3)}, "P0"),
        ({"Q": np.array([[1.0, 2.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]])}, "symmetric"),
        ({"R": np.ones((3, 3))}, "R"),
        ({"x0": [0.0, 1.0]}, "x0"),
        ({"x0": [0.0, np.nan, 1.0]}, "x0"),
        ({"solver": "mosek"}, "unknown solver"),
        ({"inconsistency": "ignore"}, "inconsistency"),
        ({"horizon": 5}, "unknown setting"),
        ({"solver": 3}, "solver"),
    ],
)
def test_bad_construction_is_a_value_error(system, kwargs, message):
    model = system[0]
    with pytest.raises(ValueError, match=message):
        pe.Estimator("smf", model, **kwargs)


def test_bad_names_and_models_are_value_errors(system):
    model = system[0]
    with pytest.raises(ValueError) as info:
        pe.Estimator("smf", model, P0=-np.eye(3))
    assert info.value.kind == "refused-input"  # refused before any step
    with pytest.raises(ValueError, match="unknown estimator"):
        pe.Estimator("nope", model)
    with pytest.raises(ValueError, match="needs the matrices"):
        pe.KalmanFilter(pe.Model.vessel())
    with pytest.raises(ValueError, match="input range"):
        pe.Estimator("yang-li", model)
    with pytest.raises(ValueError, match="noise boxes"):
        pe.MovingHorizonEstimator(model)
    with pytest.raises(ValueError, match="non-finite|not finite|NaN"):
        pe.Model(np.full((2, 2), np.nan), np.zeros((2, 1)), np.eye(2))
    with pytest.raises(ValueError, match="square"):
        pe.Model(np.zeros((2, 3)), np.zeros((2, 1)), np.eye(2))


def test_inconsistent_data_raise_with_step_and_excess_and_change_nothing(system):
    model, q, r, p0, us, ys = system
    smf = pe.SetMembershipFilter(model, P0=p0, Q=q, R=r)
    clean = pe.SetMembershipFilter(model, P0=p0, Q=q, R=r)
    for k in range(10):
        smf.step(us[k], ys[k])
        clean.step(us[k], ys[k])
    snap = _snapshot(smf)
    with pytest.raises(pe.InconsistentDataError) as info:
        smf.step(us[10], ys[10] + 1e3)
    assert info.value.step == 11 and info.value.excess > 1.0 and info.value.row is None
    assert "inconsistent" in str(info.value)
    _assert_same(smf, snap)
    for k in range(10, 20):
        e, f = smf.step(us[k], ys[k]), clean.step(us[k], ys[k])
        np.testing.assert_array_equal(e.center, f.center)
        np.testing.assert_array_equal(e.shape, f.shape)


def test_inconsistent_data_in_a_run_name_the_row_and_keep_the_rows_before(system):
    model, q, r, p0, us, ys = system
    bad = ys.copy()
    bad[17] += 1e3
    smf = pe.SetMembershipFilter(model, P0=p0, Q=q, R=r)
    with pytest.raises(pe.InconsistentDataError) as info:
        smf.run(us, bad)
    assert info.value.row == 17 and info.value.step == 18
    assert "row 17" in str(info.value)
    before = pe.SetMembershipFilter(model, P0=p0, Q=q, R=r)
    before.run(us[:17], ys[:17])
    np.testing.assert_array_equal(smf.x, before.x)
    np.testing.assert_array_equal(smf.P, before.P)


def test_flagged_inconsistent_data_are_published_and_marked(system):
    model, q, r, p0, us, ys = system
    bad = ys.copy()
    bad[5] += 1e3
    log = pe.SetMembershipFilter(model, P0=p0, Q=q, R=r, inconsistency="flag").run(us, bad)
    assert "inconsistent" in log.status[5] and "not-guaranteed" in log.status[5]
    assert all(s.endswith("not-guaranteed") for s in log.status[5:])
    assert all(log.clean[:5]) and not any(log.clean[5:])


def test_a_numerical_failure_is_a_numerical_error_and_changes_nothing():
    model = pe.Model(np.eye(2) * 1e200, np.zeros((2, 1)), np.eye(2))
    kf = pe.KalmanFilter(model, P0=1.0, Q=1.0, R=1.0)
    snap = _snapshot(kf)
    with pytest.raises(pe.NumericalError) as info:
        kf.step([0.0], [1.0, 1.0])
    assert info.value.kind == "numerical-failure"  # estimators::ErrorKind's label
    _assert_same(kf, snap)
    with pytest.raises(pe.NumericalError) as info:
        kf.run(np.zeros((3, 1)), np.ones((3, 2)))
    assert info.value.row == 0
    _assert_same(kf, snap)


def test_operations_an_estimator_does_not_offer_are_estimation_errors(system):
    model, q, r, p0, us, ys = system
    smf = pe.SetMembershipFilter(model, P0=p0, Q=q, R=r)
    snap = _snapshot(smf)
    with pytest.raises(pe.EstimationError, match="no prediction to update") as info:
        smf.update(ys[0])
    assert info.value.kind == "unsupported"
    _assert_same(smf, snap)
    w, v = np.full(3, 0.1), np.full(2, 0.1)
    mhe = pe.MovingHorizonEstimator(model, R=np.diag(np.diag(r)), w_lower=-w, w_upper=w, v_lower=-v, v_upper=v)
    with pytest.raises(pe.EstimationError, match="does not offer"):
        mhe.update(ys[0])


def test_unaligned_arrays_are_read_as_their_values(system):
    """NumPy arrays in unaligned memory (as Dask unpickles them from out-of-band buffers) are
    copied, not viewed: the same numbers, no error, no panic."""
    model, q, r, p0, us, ys = system

    def unaligned(a):
        a = np.ascontiguousarray(a, dtype=float)
        raw = np.zeros(a.nbytes + 1, dtype=np.uint8)
        view = raw[1:].view(np.float64).reshape(a.shape)
        view[...] = a
        assert not view.flags.aligned
        return view

    aligned = pe.KalmanFilter(model, P0=p0, Q=q, R=r).run(us, ys)
    shifted = pe.KalmanFilter(model, P0=unaligned(p0), Q=unaligned(q), R=unaligned(r))
    np.testing.assert_array_equal(shifted.run(unaligned(us), unaligned(ys)).center, aligned.center)
    np.testing.assert_array_equal(shifted.step(unaligned(us[0]), unaligned(ys[0])).center, shifted.x)


def test_the_innovation_gate_raises_flags_restarts_or_stays_silent_as_asked(system):
    model, q, r, p0, us, ys = system
    bad = ys[10] + 1e3

    def warmed(policy):
        kf = pe.KalmanFilter(model, P0=p0, Q=q, R=r)
        kf.set_data_checks(policy)
        for k in range(10):
            kf.step(us[k], ys[k])
        return kf

    kf = warmed("error")
    snap = _snapshot(kf)
    with pytest.raises(pe.InconsistentDataError) as info:
        kf.step(us[10], bad)
    assert info.value.step == 11 and info.value.nis > info.value.threshold > 0.0
    assert info.value.probability == 1.0 - 1e-12
    _assert_same(kf, snap)

    predicted = warmed("off")
    predicted.predict(us[10])
    e = warmed("restart").step(us[10], bad)
    assert "inconsistent" in e.status
    np.testing.assert_array_equal(e.center, predicted.x)

    flagged = warmed("flag").step(us[10], bad)
    assert "inconsistent" in flagged.status
    assert np.max(np.abs(flagged.center - predicted.x)) > 1.0

    silent = warmed("off").step(us[10], bad)
    assert "inconsistent" not in silent.status
    np.testing.assert_array_equal(silent.center, flagged.center)

    with pytest.raises(ValueError, match="policy"):
        kf.set_data_checks("sometimes")
    with pytest.raises(ValueError):
        kf.set_data_checks("error", gate_probability=1.5)


def test_vehicle_parameters_are_refused_by_name():
    with pytest.raises(ValueError, match="sub-steps per sampling period must be in 1..=10000, got 0"):
        pe.Model.vessel(rk4_substeps=0)
    # A count that would hold the interpreter for hours is refused before any evaluation.
    with pytest.raises(ValueError, match="got 1000000000000"):
        pe.Model.vessel(rk4_substeps=10**12)
    with pytest.raises(ValueError, match="load must be 0, 1 or 2 containers, got -1"):
        pe.Model.carrier(load=-1)


@pytest.mark.parametrize(
    ("value", "words"),
    [
        (np.array([0.29 + 5j]), "complex numbers"),
        (np.array([True]), "booleans"),
        (["0.3"], "strings"),
        (np.ma.masked_array([0.3], mask=[True]), "masked array"),
    ],
)
def test_only_real_numbers_are_taken(value, words):
    kf = pe.KalmanFilter(pe.Model(np.eye(1), np.zeros((1, 0)), np.eye(1)), x0=np.zeros(1), P0=1.0, Q=1e-2, R=1e-2)
    with pytest.raises(ValueError, match=words):
        kf.update(value)
    assert kf.x[0] == 0.0


def test_a_run_refusing_a_later_row_raises_run_error_and_keeps_the_rows_before(system):
    model, q, r, p0, us, ys = system
    box = {"u_lower": -np.ones(1), "u_upper": np.ones(1)}
    bad = us.copy()
    bad[9] = 5.0  # outside the input box
    est = pe.Estimator("yang-li", model, P0=p0, Q=q, R=r, **box)
    with pytest.raises(pe.RunError) as info:
        est.run(bad, ys)
    assert not isinstance(info.value, ValueError)
    assert info.value.row == 9 and "row 9" in str(info.value)
    before = pe.Estimator("yang-li", model, P0=p0, Q=q, R=r, **box)
    before.run(us[:9], ys[:9])
    np.testing.assert_array_equal(est.x, before.x)
    # The same value in the first row: nothing was done, a ValueError.
    fresh = pe.Estimator("yang-li", model, P0=p0, Q=q, R=r, **box)
    snap = _snapshot(fresh)
    with pytest.raises(ValueError) as info:
        fresh.run(bad[9:], ys[9:])
    assert info.value.row == 0
    _assert_same(fresh, snap)


@pytest.mark.parametrize(("name", "vehicle"), [("kf", pe.Model.car), ("ekf", pe.Model.vessel), ("ukf", pe.Model.vessel)])
def test_a_cell_beyond_floating_point_fails_its_own_row_even_with_the_data_check_off(name, vehicle):
    # Accepted, the 1e160 cell would move the estimate out of range and fail a later row (one
    # later for the EKF, sixteen for the UKF) as if the model were to blame.
    model = vehicle()
    n, p, m = model.dims
    rng = np.random.default_rng(1)
    us, ys, x = np.zeros((30, p)), np.zeros((30, m)), np.zeros(n)
    for k in range(30):
        x = model.f(x, us[k])
        ys[k] = model.h(x, us[k]) + 0.01 * rng.normal(size=m)
    ys[10, 0] = 1e160

    def build():
        est = pe.Estimator(name, model, P0=np.eye(n), Q=1e-4 * np.eye(n), R=1e-2 * np.eye(m))
        est.set_data_checks("off")
        return est

    est = build()
    with pytest.raises(pe.NumericalError, match="normalised innovation overflows") as info:
        est.run(us, ys)
    assert info.value.row == 10
    before = build()
    before.run(us[:10], ys[:10])
    np.testing.assert_array_equal(est.x, before.x)
