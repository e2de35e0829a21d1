"""Shared helpers of the package's tests: random systems, simulation, tolerances."""

from __future__ import annotations

import numpy as np
import pytest

import port_estimation as pe


def random_system(rng: np.random.Generator, n: int = 4, p: int = 2, m: int = 3, *, diagonal_r: bool = False):
    """A random stable linear system ``(A, B, C)`` and SPD ``Q``, ``R``, ``P0`` of sensible scale."""
    a = rng.normal(size=(n, n))
    a *= 0.97 / max(abs(np.linalg.eigvals(a)))
    b = rng.normal(size=(n, p))
    c = rng.normal(size=(m, n))

    def spd(k: int, scale: float) -> np.ndarray:
        g = rng.normal(size=(k, k))
        return scale * (g @ g.T / k + np.eye(k))

    q, p0 = spd(n, 1e-2), spd(n, 1.0)
    r = np.diag(rng.uniform(0.05, 0.2, size=m)) if diagonal_r else spd(m, 1e-1)
    return a, b, c, q, r, p0


def simulate_gaussian(rng, a, b, c, q, r, x0, steps):
    """``x[k+1] = A x[k] + B u[k] + w``, ``y[k+1] = C x[k+1] + v`` with Gaussian noise; returns us, ys, xs."""
    n, p = b.shape
    us = rng.normal(size=(steps, p))
    lq, lr = np.linalg.cholesky(q), np.linalg.cholesky(r)
    xs, ys = np.zeros((steps, n)), np.zeros((steps, c.shape[0]))
    x = np.array(x0, dtype=float)
    for k in range(steps):
        x = a @ x + b @ us[k] + lq @ rng.normal(size=n)
        xs[k] = x
        ys[k] = c @ x + lr @ rng.normal(size=c.shape[0])
    return us, ys, xs


def on_boundary(rng, shape: np.ndarray) -> np.ndarray:
    """A point on the boundary of the ellipsoid ``{z : z' shape^-1 z <= 1}``."""
    z = rng.normal(size=shape.shape[0])
    return np.linalg.cholesky(shape) @ (z / np.linalg.norm(z))


def assert_close(ours, reference, rtol: float = 1e-9, what: str = "") -> None:
    """``ours`` equals ``reference`` to ``rtol`` relative to the reference's largest entry."""
    ours, reference = np.asarray(ours), np.asarray(reference)
    scale = max(np.abs(reference).max(), 1e-300)
    err = np.abs(ours - reference).max() / scale
    assert err <= rtol, f"{what}: relative difference {err:.3e} > {rtol:.0e}"


@pytest.fixture
def rng() -> np.random.Generator:
    return np.random.default_rng(20240601)


@pytest.fixture
def linear():
    """A small random linear model and its noise matrices."""
    r = np.random.default_rng(7)
    a, b, c, q, rr, p0 = random_system(r, 3, 1, 2, diagonal_r=True)
    return pe.Model(a, b, c), q, rr, p0
