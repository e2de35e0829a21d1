"""The Gaussian filters against filterpy, an independent implementation, at every step to 1e-9.

Conventions (``crates/estimators/src/ukf.rs``, ``ekf.rs``): one step consumes ``u[k]`` and the
measurement ``y[k+1]`` taken after it; ``h`` is evaluated with the step's input; the EKF's ``F`` at the
previous estimate and ``H`` at the prediction; the UKF draws its sigma points again from the
prediction before the update (filterpy 2 does the same at the end of ``predict``) and updates with
``P - K S K'``; the Kalman filters use the Joseph form (as filterpy's ``update``).
"""

from __future__ import annotations

import numpy as np
import pytest
from conftest import assert_close, random_system, simulate_gaussian
from filterpy.kalman import ExtendedKalmanFilter as FilterpyEKF
from filterpy.kalman import KalmanFilter as FilterpyKF
from filterpy.kalman import MerweScaledSigmaPoints
from filterpy.kalman import UnscentedKalmanFilter as FilterpyUKF

import port_estimation as pe


@pytest.mark.parametrize("seed", range(5))
def test_kalman_filter_equals_filterpy_at_every_step(seed):
    rng = np.random.default_rng(seed)
    n, p, m = [(4, 2, 3), (2, 1, 1), (6, 3, 2), (5, 1, 5), (3, 2, 2)][seed]
    a, b, c, q, r, p0 = random_system(rng, n, p, m)
    x0 = rng.normal(size=n)
    us, ys, _ = simulate_gaussian(rng, a, b, c, q, r, x0, 200)

    ours = pe.KalmanFilter(pe.Model(a, b, c), x0=x0, P0=p0, Q=q, R=r)
    ref = FilterpyKF(dim_x=n, dim_z=m, dim_u=p)
    ref.x, ref.P, ref.F, ref.B, ref.H, ref.Q, ref.R = x0.copy(), p0.copy(), a, b, c, q, r
    for k in range(len(us)):
        if k % 2:
            e = ours.step(us[k], ys[k])
        else:
            ours.predict(us[k])
            e = ours.update(ys[k])
        ref.predict(u=us[k])
        ref.update(ys[k])
        assert_close(e.center, ref.x, what=f"x at step {k}")
        assert_close(e.shape, ref.P, what=f"P at step {k}")
    assert_close(ours.x, ref.x)


class _ModelEKF(FilterpyEKF):
    """filterpy's EKF with the model's ``f`` for the prediction of the state."""

    def __init__(self, model: pe.Model):
        n, p, m = model.dims
        super().__init__(dim_x=n, dim_z=m, dim_u=p)
        self.model = model

    def predict_x(self, u=0):
        self.x = self.model.f(self.x, u)


def _truck_log(rng, steps):
    """Inputs and noisy measurements of the truck in a gentle weave at about 10 m/s."""
    model = pe.Model.truck()
    re = 0.52
    x = np.array([10.0, 0.0, 0.0])
    us, ys = np.zeros((steps, 7)), np.zeros((steps, 3))
    for k in range(steps):
        delta = 0.03 * np.sin(2 * np.pi * k / 400)
        us[k] = [delta] + [10.2 / re] * 6
        x = model.f(x, us[k])
        ys[k] = model.h(x, us[k]) + rng.normal(scale=[0.05, 0.1, 0.005])
    return model, us, ys, np.array([9.5, 0.1, 0.0])


def _vessel_log(rng, steps):
    """Thrust and noisy position measurements of the supply vessel turning slowly."""
    model = pe.Model.vessel()
    x = np.array([0.0, 0.0, 0.1, 1.0, 0.1, 0.01])
    us, ys = np.zeros((steps, 3)), np.zeros((steps, 3))
    for k in range(steps):
        us[k] = [2e5 * np.cos(k / 30), 5e4 * np.sin(k / 20), 1e6 * np.sin(k / 50)]
        x = model.f(x, us[k])
        ys[k] = model.h(x, us[k]) + rng.normal(scale=[0.5, 0.5, 0.01])
    return model, us, ys, np.array([0.5, -0.5, 0.05, 0.8, 0.0, 0.0])


def _linear_log(rng, steps):
    a, b, c, q, r, p0 = random_system(rng, 4, 2, 3)
    x0 = rng.normal(size=4)
    us, ys, _ = simulate_gaussian(rng, a, b, c, q, r, x0, steps)
    return pe.Model(a, b, c), us, ys, x0


LOGS = {"truck": _truck_log, "vessel": _vessel_log, "random linear": _linear_log}


@pytest.mark.parametrize("log", LOGS)
def test_extended_kalman_filter_equals_filterpy_at_every_step(log):
    rng = np.random.default_rng(11)
    model, us, ys, x0 = LOGS[log](rng, 150)
    n, _, m = model.dims
    p0, q, r = np.eye(n) * 0.5, np.eye(n) * 1e-4, np.eye(m) * 1e-2
    ours = pe.ExtendedKalmanFilter(model, x0=x0, P0=p0, Q=q, R=r)
    # filterpy has no innovation gate; these logs' first steps fail ours (NIS ~ 100 against 59).
    ours.set_data_checks("off")
    ref = _ModelEKF(model)
    ref.x, ref.P, ref.Q, ref.R = x0.copy(), p0.copy(), q, r
    for k, (u, y) in enumerate(zip(us, ys)):
        e = ours.step(u, y)
        ref.F = model.F(ref.x, u)
        ref.predict(u=u)
        ref.update(y, HJacobian=lambda x, u=u: model.H(x, u), Hx=lambda x, u=u: model.h(x, u))
        assert_close(e.center, ref.x, what=f"{log}: x at step {k}")
        assert_close(e.shape, ref.P, what=f"{log}: P at step {k}")


@pytest.mark.parametrize("log", LOGS)
@pytest.mark.parametrize(("alpha", "beta", "kappa"), [(1.0, 2.0, 0.0), (0.5, 2.0, 1.0), (0.3, 2.0, -1.0)])
def test_unscented_kalman_filter_equals_filterpy_at_every_step(log, alpha, beta, kappa):
    rng = np.random.default_rng(12)
    model, us, ys, x0 = LOGS[log](rng, 150)
    n, _, m = model.dims
    p0, q, r = np.eye(n) * 0.5, np.eye(n) * 1e-4, np.eye(m) * 1e-2
    ours = pe.UnscentedKalmanFilter(model, x0=x0, P0=p0, Q=q, R=r, alpha=alpha, beta=beta, kappa=kappa)
    # filterpy has no innovation gate; these logs' first steps fail ours (NIS ~ 100 against 59).
    ours.set_data_checks("off")
    points = MerweScaledSigmaPoints(n, alpha=alpha, beta=beta, kappa=kappa)
    ref = FilterpyUKF(dim_x=n, dim_z=m, dt=None, fx=lambda x, dt, u: model.f(x, u), hx=None, points=points)
    ref.x, ref.P, ref.Q, ref.R = x0.copy(), p0.copy(), q, r
    for k, (u, y) in enumerate(zip(us, ys)):
        e = ours.step(u, y)
        assert e.status == "converged", f"{log}: step {k} used the positive-definiteness guard"
        ref.predict(u=u)
        ref.update(y, hx=lambda x, u=u: model.h(x, u))
        assert_close(e.center, ref.x, what=f"{log}: x at step {k}")
        assert_close(e.shape, ref.P, what=f"{log}: P at step {k}")


def test_singular_covariances_are_covariances_and_match_filterpy():
    # A constant-velocity target with filterpy's rank-one white-noise Q and a singular P0 (the
    # velocity known exactly): the Kalman filter and the EKF take them, the UKF takes the Q (its
    # sigma points need a definite P0), and all follow filterpy.
    from filterpy.common import Q_discrete_white_noise

    dt = 0.1
    a = np.array([[1.0, dt], [0.0, 1.0]])
    b, c = np.array([[0.5 * dt * dt], [dt]]), np.array([[1.0, 0.0]])
    q = Q_discrete_white_noise(dim=2, dt=dt, var=0.5)
    assert np.linalg.matrix_rank(q) == 1
    r, p0 = np.array([[0.04]]), np.diag([1.0, 0.0])
    rng = np.random.default_rng(3)
    us, ys, _ = simulate_gaussian(rng, a, b, c, q + 1e-12 * np.eye(2), r, [0.0, 1.0], 100)
    model = pe.Model(a, b, c)
    for name, prior in [("kf", p0), ("ekf", p0), ("ukf", np.eye(2)), ("kf", np.zeros((2, 2)))]:
        for noise in [q, np.zeros((2, 2))]:
            ours = pe.Estimator(name, model, x0=[0.0, 1.0], P0=prior, Q=noise, R=r)
            # (With Q = 0 the filter is certain of a target that does move: its gate would stop it.)
            ours.set_data_checks("off")
            ref = FilterpyKF(dim_x=2, dim_z=1, dim_u=1)
            ref.x, ref.P, ref.F, ref.B, ref.H, ref.Q, ref.R = np.array([0.0, 1.0]), prior.copy(), a, b, c, noise, r
            for k in range(len(us)):
                e = ours.step(us[k], ys[k])
                ref.predict(u=us[k])
                ref.update(ys[k])
                assert_close(e.center, ref.x, rtol=1e-6, what=f"{name} x at step {k}")
                assert_close(e.shape, ref.P, rtol=1e-6, what=f"{name} P at step {k}")
    # Indefinite beyond rounding is refused by name; so is a singular R, and the UKF's singular P0.
    with pytest.raises(ValueError, match="Q is not positive semidefinite"):
        pe.KalmanFilter(model, Q=np.diag([1.0, -1e-6]), R=r)
    with pytest.raises(ValueError, match="R is not positive definite"):
        pe.KalmanFilter(model, Q=q, R=np.zeros((1, 1)))
    with pytest.raises(ValueError, match="P0 is not positive definite"):
        pe.UnscentedKalmanFilter(model, P0=p0, Q=q, R=r)
