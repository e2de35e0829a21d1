"""Resources: every keyword that sizes an estimator's buffers or its time is checked before
anything is allocated (a ValueError naming it, never an aborted interpreter), and long calls let
other threads and Ctrl-C through."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

import port_estimation as pe

ROOT = Path(__file__).resolve().parents[3]


def _boxes(n: int, m: int) -> dict:
    return {"w_lower": -np.ones(n), "w_upper": np.ones(n), "v_lower": -np.ones(m), "v_upper": np.ones(m)}


def _linear():
    a = np.array([[1.0, 0.1], [0.0, 0.9]])
    return pe.Model(a, np.array([[0.0], [0.1]]), np.array([[1.0, 0.0]]))


@pytest.mark.parametrize("horizon", [100_000, 10**9, 2**62])
def test_a_linear_window_beyond_the_memory_limit_is_refused_by_name(horizon):
    with pytest.raises(ValueError, match=rf"setting horizon: a horizon of N = {horizon} .* more than the limit of 256 MiB \(raise it with memory_limit="):
        pe.MovingHorizonEstimator(_linear(), R=np.eye(1), horizon=horizon, **_boxes(2, 1))
    with pytest.raises(ValueError, match="horizon"):
        pe.Estimator("rmhe", _linear(), R=np.eye(1), horizon=horizon, preset="rmhe-of", **_boxes(2, 1))


def test_the_memory_limit_is_a_setting_and_a_window_inside_it_is_built():
    model = _linear()
    with pytest.raises(ValueError, match=r"setting horizon: a horizon of N = 400 .* more than the limit of 1 MiB"):
        pe.MovingHorizonEstimator(model, R=np.eye(1), horizon=400, memory_limit=1 << 20, **_boxes(2, 1))
    mhe = pe.MovingHorizonEstimator(model, R=np.eye(1), horizon=400, memory_limit=1 << 30, **_boxes(2, 1))
    assert mhe.step(np.zeros(1), np.zeros(1)).status == "converged"
    with pytest.raises(ValueError, match="setting memory_limit must be a non-negative integer, got -1"):
        pe.MovingHorizonEstimator(model, R=np.eye(1), memory_limit=-1, **_boxes(2, 1))


def test_a_model_files_window_grown_by_a_keyword_is_refused():
    mf = pe.read_model(ROOT / "examples" / "models" / "car.toml")
    with pytest.raises(ValueError, match=r"setting horizon: a horizon of N = 100000 .* more than the limit of"):
        mf.estimator("rmhe", horizon=100_000)


@pytest.mark.parametrize("horizon", [10**6, 10**9, 2**62])
def test_a_nonlinear_window_beyond_the_memory_limit_is_refused_by_name(horizon):
    with pytest.raises(ValueError, match=rf"setting horizon: a horizon of N = {horizon} needs .* more than the limit of"):
        pe.NonlinearMHE(pe.Model.vessel(), horizon=horizon)


def test_iteration_counts_are_bounded():
    with pytest.raises(ValueError, match="setting max_sweeps: at most 10000 sweeps .* per window, got 10001"):
        pe.MovingHorizonEstimator(_linear(), R=np.eye(1), max_sweeps=10_001, **_boxes(2, 1))
    with pytest.raises(ValueError, match="setting max_iterations: at most 10000 sweeps .* per window, got 1000000"):
        pe.NonlinearMHE(pe.Model.vessel(), max_iterations=10**6)
    for k in (0, 11, 10**6):
        with pytest.raises(ValueError, match=f"real_time_iterations must be between 1 and 10, got {k}"):
            pe.NonlinearMHE(pe.Model.vessel(), real_time_iterations=k)


def test_real_time_iterations_spend_their_budget_and_say_so():
    model = pe.Model.vessel()
    rng = np.random.default_rng(3)
    full, fast = pe.NonlinearMHE(model), pe.NonlinearMHE(model, real_time_iterations=1)
    x = np.zeros(6)
    for k in range(30):
        u = np.array([1e5, 5e4 * np.sin(0.1 * k), 1e6 * np.cos(0.05 * k)])
        x = model.f(x, u)
        y = model.h(x, u) + rng.normal(size=3) * np.array([1.0, 1.0, 0.3])
        a, b = full.step(u, y), fast.step(u, y)
        assert b.status == "real-time" and b.clean and b.details["iterations"] == 1
        assert a.status == "converged"
    # One iteration from the previous window stays within a fraction of a standard deviation.
    assert np.max(np.abs(a.center - b.center) / np.sqrt(np.diag(a.shape))) < 0.2


def _long_log(rows: int):
    rng = np.random.default_rng(7)
    us = rng.uniform(-1, 1, size=(rows, 1))
    ys = rng.normal(scale=0.1, size=(rows, 1))
    return us, ys


def _ukf():
    return pe.UnscentedKalmanFilter(_linear(), P0=np.eye(2), Q=1e-2 * np.eye(2), R=np.eye(1))


def test_ctrl_c_stops_a_long_run_between_rows_and_keeps_the_rows_before():
    import _thread
    import threading

    us, ys = _long_log(1_000_000)
    ukf = _ukf()
    # `interrupt_main` is what Ctrl-C does: the signal is noticed between stretches of rows.
    timer = threading.Timer(0.05, _thread.interrupt_main)
    timer.start()
    with pytest.raises(KeyboardInterrupt) as info:
        ukf.run(us, ys)
    timer.join()
    row = info.value.row
    assert 0 < row < len(ys), row
    before = _ukf()
    before.run(us[:row], ys[:row])
    np.testing.assert_array_equal(ukf.x, before.x)
    np.testing.assert_array_equal(ukf.P, before.P)


def test_other_threads_run_and_read_while_a_long_run_goes_on():
    import threading

    us, ys = _long_log(1_000_000)
    ukf = _ukf()
    result = {}
    runner = threading.Thread(target=lambda: result.setdefault("run", ukf.run(us, ys)))
    runner.start()
    while ukf.estimate.status == "initial" and runner.is_alive():
        pass
    # Reading the estimate waits for the current stretch of rows, not for the whole run.
    x = ukf.x
    assert runner.is_alive(), "the read waited for the end of the run"
    runner.join()
    centres = result["run"].center
    assert any(np.array_equal(x, c) for c in centres[: len(centres) // 2]), x


def test_a_model_file_cannot_lift_its_memory_limit_but_a_keyword_can():
    text = (ROOT / "examples" / "models" / "car.toml").read_text()
    assert "[mhe]" in text
    lifted = text.replace("[mhe]\n", "[mhe]\nmemory_limit = 1000000000000\n", 1)
    with pytest.raises(ValueError, match=r"`mhe.memory_limit`: 1000000000000 bytes is above the limit of 256 MiB"):
        pe.parse_model(lifted, "car.toml")
    mf = pe.read_model(ROOT / "examples" / "models" / "car.toml")
    with pytest.raises(ValueError, match="more than the limit of 256 MiB"):
        mf.estimator("rmhe", horizon=800)
    # The caller's keyword lifts it (refused here only by the window's own size, nothing built).
    with pytest.raises(ValueError, match=r"more than the limit of 1 GiB"):
        mf.estimator("rmhe", horizon=100_000, memory_limit=1 << 30)


def test_sigma_points_of_an_arrival_cost_that_has_none_are_refused():
    for arrival in ("extended", "fixed"):
        with pytest.raises(ValueError, match=r'setting kappa: kappa sets the sigma points of arrival = "unscented"'):
            pe.NonlinearMHE(pe.Model.vessel(), arrival=arrival, kappa=1.0)
    assert pe.NonlinearMHE(pe.Model.vessel(), arrival="unscented", kappa=1.0) is not None
