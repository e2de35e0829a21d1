"""Models written as equations (``Model.from_equations``): a linear one equals ``Model(A, B, C)``
and its Kalman filter bit for bit; a nonlinear one's Jacobians against central differences, its
EKF and UKF running; errors at ``file:line:column``; pickling by the text."""

from __future__ import annotations

import pickle
from pathlib import Path

import numpy as np
import pytest

import port_estimation as pe

MODELS = Path(__file__).resolve().parent / "models"
LINEAR = (MODELS / "linear.toml").read_text()
PENDULUM = (MODELS / "pendulum.toml").read_text()


def test_a_linear_model_written_as_equations_is_the_matrix_model():
    eq = pe.Model.from_equations(LINEAR, "linear.toml")
    assert eq.dims == (2, 1, 1) and eq.capability == "linear"
    a, b, c = np.array([[1.0, 0.1], [0.0, 0.9]]), np.array([[0.0], [0.1]]), np.array([[1.0, 0.0]])
    np.testing.assert_array_equal(eq.A, a)
    np.testing.assert_array_equal(eq.B, b)
    np.testing.assert_array_equal(eq.C, c)
    rng = np.random.default_rng(5)
    us, ys, x = rng.normal(size=(200, 1)), np.zeros((200, 1)), np.zeros(2)
    for k in range(200):
        x = a @ x + b @ us[k] + rng.normal(scale=0.03, size=2)
        ys[k] = c @ x + rng.normal(scale=0.3, size=1)
    ours = pe.KalmanFilter(eq, P0=1.0, Q=1e-3, R=0.1).run(us, ys)
    reference = pe.KalmanFilter(pe.Model(a, b, c), P0=1.0, Q=1e-3, R=0.1).run(us, ys)
    np.testing.assert_array_equal(ours.center, reference.center)


def test_a_nonlinear_model_has_exact_jacobians_and_runs_the_ekf_and_ukf():
    m = pe.Model.from_equations(PENDULUM, "pendulum.toml")
    assert m.dims == (2, 1, 2) and m.capability == "second-order"
    rng = np.random.default_rng(8)
    for _ in range(10):
        x, u = rng.uniform(-1.5, 1.5, size=2), rng.uniform(-1, 1, size=1)
        eps = 1e-6
        fd = np.column_stack([(m.f(x + eps * e, u) - m.f(x - eps * e, u)) / (2 * eps) for e in np.eye(2)])
        np.testing.assert_allclose(m.F(x, u), fd, rtol=1e-6, atol=1e-8)
        hd = np.column_stack([(m.h(x + eps * e, u) - m.h(x - eps * e, u)) / (2 * eps) for e in np.eye(2)])
        np.testing.assert_allclose(m.H(x, u), hd, rtol=1e-6, atol=1e-8)
    # A simulated swing, filtered: both filters end near the truth.
    x, us, ys, truth = np.array([0.6, 0.0]), [], [], []
    for k in range(300):
        u = np.array([0.2 * np.sin(0.05 * k)])
        x = m.f(x, u)
        us.append(u)
        ys.append(m.h(x, u) + rng.normal(scale=0.01, size=2))
        truth.append(x)
    for est in (pe.ExtendedKalmanFilter, pe.UnscentedKalmanFilter):
        run = est(m, x0=[0.3, 0.0], P0=0.5, Q=1e-6, R=1e-4).run(np.array(us), np.array(ys))
        assert np.max(np.abs(run.center[-50:] - np.array(truth)[-50:])) < 0.05, est.__name__


def test_bad_equations_are_value_errors_at_their_location():
    with pytest.raises(ValueError, match=r"bad\.toml:15:1: .*unknown symbol `wobble`"):
        pe.Model.from_equations(PENDULUM.replace('"omega"\n', '"wobble"\n', 1), "bad.toml")
    with pytest.raises(ValueError, match=r"<string>:\d+:\d+"):
        pe.Model.from_equations("[model]\nstates = [1]\n")


def test_equation_models_pickle_by_their_text():
    m = pe.Model.from_equations(PENDULUM, "pendulum.toml")
    back = pickle.loads(pickle.dumps(m))
    x, u = np.array([0.3, -0.2]), np.array([0.1])
    np.testing.assert_array_equal(back.f(x, u), m.f(x, u))
    assert repr(back) == repr(m)


ROOT = Path(__file__).resolve().parents[3]


def test_a_port_est_model_file_of_equations_runs_the_vessel_log_as_port_est_does():
    mf = pe.read_model(ROOT / "examples" / "models" / "vessel.toml")
    assert mf.model.dims == (6, 3, 3) and mf.model.capability == "second-order"
    data = np.loadtxt(ROOT / "examples" / "vessel" / "data.csv", delimiter=",", skiprows=1)
    truth = np.loadtxt(ROOT / "examples" / "vessel" / "truth.csv", delimiter=",", skiprows=1)
    us, ys = data[:, 1:4], data[:, 4:7]
    for name in ["ekf", "ukf"]:
        log = mf.estimator(name).run(us, ys)
        rms = np.sqrt(np.mean((log.center[100:, :3] - truth[100:, 1:4]) ** 2, axis=0))
        assert np.all(rms[:2] < 0.6) and rms[2] < 0.25, (name, rms)
    # The file's [ukf] table (the paper's 0.5, 2, -2) is the unscented filter's default; keywords
    # override it.
    paper = mf.estimator("ukf", alpha=0.5, beta=2.0, kappa=-2.0).run(us[:50], ys[:50]).center
    np.testing.assert_array_equal(mf.estimator("ukf").run(us[:50], ys[:50]).center, paper)
    other = mf.estimator("ukf", alpha=1.0, beta=2.0, kappa=0.0).run(us[:50], ys[:50]).center
    assert not np.array_equal(other, paper)
    # Linear estimators are refused with the reason; pickling keeps the equations.
    with pytest.raises(ValueError, match="linear"):
        mf.estimator("kf")
    again = pickle.loads(pickle.dumps(mf))
    np.testing.assert_array_equal(again.estimator("ekf").run(us, ys).center, mf.estimator("ekf").run(us, ys).center)
