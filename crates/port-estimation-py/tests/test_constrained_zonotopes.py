"""The constrained-zonotope filters from Python: boxes as generator matrices (a box needs no
ellipsoid), the set itself readable as (c, G, A, b), the truth inside with noise on the boundary of
its boxes, and CORA's six-tank benchmark from its model file."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

import port_estimation as pe

ROOT = Path(__file__).resolve().parents[3]


# A double integrator (position measured, acceleration as input) as a model file, shared with
# port-est's tests.
DOUBLE_INTEGRATOR = (ROOT / "crates" / "port-est" / "tests" / "fixtures" / "double_integrator.toml").read_text()


def test_a_linear_model_with_boxes_holds_the_truth_on_the_boundary():
    rng = np.random.default_rng(4)
    a = np.array([[0.95, 0.2], [-0.15, 0.9]])
    b = np.array([[0.1], [0.05]])
    c = np.array([[1.0, -0.5]])
    model = pe.Model(A=a, B=b, C=c)
    w, v = np.array([0.05, 0.02]), np.array([0.1])
    czf = pe.Estimator("czf", model, x0=[0.5, -0.2], P0=[1.0, 0.8], Q=w, R=v, order=10, max_constraints=4)
    x = np.array([0.5 + 1.0, -0.2 - 0.8])
    us = rng.uniform(-1, 1, size=(300, 1))
    xs, ys = np.zeros((300, 2)), np.zeros((300, 1))
    for k in range(300):
        x = a @ x + b @ us[k] + w * rng.choice([-1.0, 1.0], size=2)
        xs[k], ys[k] = x, c @ x + v * rng.choice([-1.0, 1.0], size=1)
    log = czf.run(us, ys)
    assert np.all(log.lower <= xs) and np.all(xs <= log.upper)
    assert all(s == "converged" for s in log.status)
    e = czf.estimate
    assert e.kind == "guaranteed constrained zonotope" and e.guaranteed
    cz, g, am, bm = e.set
    assert g.shape[0] == 2 and am.shape[1] == g.shape[1] and bm.shape == (am.shape[0],)
    assert g.shape[1] <= 20 and am.shape[0] <= 4


def test_bad_settings_are_value_errors():
    model = pe.Model(A=[[1.0]], B=[[0.0]], C=[[1.0]])
    with pytest.raises(ValueError, match="order"):
        pe.Estimator("czf", model, x0=[0.0], P0=[1.0], Q=[0.1], R=[0.1], order=0)
    with pytest.raises(ValueError, match="unknown setting"):
        pe.Estimator("czf", model, x0=[0.0], P0=[1.0], Q=[0.1], R=[0.1], horizon=3)


def test_cora_six_tank_from_its_model_file_beats_cora_s_published_widths():
    mf = pe.read_model(ROOT / "examples" / "six-tank" / "model.toml")
    data = np.loadtxt(ROOT / "examples" / "six-tank" / "data.csv", delimiter=",", skiprows=1)
    log = mf.estimator("czf-nl").run(data[:, 1:4], data[:, 4:7])
    widths = log.upper[-1] - log.lower[-1]
    # CORA's FRad-A (examples/six-tank/cora_hulls.csv); without CORA's update at t = 0 (the log
    # has no row for it) the sets are a little wider than the Rust test's, still far inside.
    cora = np.array([0.4900, 0.4895, 15.924, 0.6332, 0.4207, 7.5405])
    assert np.all(widths < cora), widths


def test_a_model_file_s_generator_matrices_are_the_filter_s_sets():
    base = DOUBLE_INTEGRATOR
    skewed = base + "x0_radius = [0.5, 0.5]\nw_generators = [[0.01, 0.004], [-0.004, 0.01]]\nv_radius = [0.05]\n"
    boxed = base + "x0_radius = [0.5, 0.5]\nw_radius = [0.014, 0.014]\nv_radius = [0.05]\n"
    rng = np.random.default_rng(5)
    gw = np.array([[0.01, 0.004], [-0.004, 0.01]])
    x, us, ys, truth = np.array([0.3, -0.2]), [], [], []
    for k in range(60):
        u = np.sin(0.1 * k)
        x = np.array([[1.0, 0.1], [0.0, 1.0]]) @ x + np.array([0.0, 0.1 * u]) + gw @ rng.choice([-1.0, 1.0], 2)
        us.append([u])
        ys.append([x[0] + rng.choice([-0.05, 0.05])])
        truth.append(x)
    truth = np.array(truth)
    runs = [pe.parse_model(text).estimator("czf").run(np.array(us), np.array(ys)) for text in (skewed, boxed)]
    for log in runs:
        assert np.all(log.lower <= truth) and np.all(truth <= log.upper)
    # The skewed zonotope is tighter than the box around it (its hull, w_radius = row sums).
    assert np.sum(runs[0].upper - runs[0].lower) < np.sum(runs[1].upper - runs[1].lower)
    with pytest.raises(ValueError, match="not both"):
        pe.parse_model(skewed + "w_radius = [0.1, 0.1]\n")


MODEL_WITH_TABLE = DOUBLE_INTEGRATOR + """\
x0_radius = [0.5, 0.5]
w_radius = [0.01, 0.01]
v_radius = [0.05]

[estimator.czf]
order = 2
max_constraints = 1
"""


def test_a_model_file_s_estimator_table_is_read_and_keywords_go_over_it():
    us = np.sin(0.1 * np.arange(60))[:, None]
    x, ys = np.array([0.3, -0.2]), np.zeros((60, 1))
    for k in range(60):
        x = np.array([x[0] + 0.1 * x[1], x[1] + 0.1 * us[k, 0]])
        ys[k] = x[0] + (0.05 if k % 5 < 2 else -0.05)
    def generators(est):
        return est.run(us, ys).details["generators"]

    table = pe.parse_model(MODEL_WITH_TABLE, "m.toml")
    # The table's order 2: 2 n = 4 generators at most; a keyword over it: 6 per state.
    assert max(generators(table.estimator("czf"))) <= 4
    assert max(generators(table.estimator("czf", order=6))) > 4
    untabled = pe.parse_model(MODEL_WITH_TABLE.split("[estimator.czf]")[0], "m.toml")
    assert max(generators(untabled.estimator("czf"))) > 4
    # A mistake in the table is at its line and column, as port-est says it.
    with pytest.raises(ValueError, match=r"m.toml:13:9: `estimator.czf.order`: must be a non-negative integer"):
        pe.parse_model(MODEL_WITH_TABLE.replace("order = 2", 'order = "two"'), "m.toml")
    # A keyword's mistake names the keyword; an unknown one names what the estimator takes.
    with pytest.raises(ValueError, match="setting order must be a non-negative integer"):
        table.estimator("czf", order="one")
    with pytest.raises(ValueError, match=r"unknown setting\(s\) horizon for estimator czf \(it takes: order,"):
        table.estimator("czf", horizon=3)
    # A setting of the table that the filter refuses when built: at its key too.
    too_many = pe.parse_model(MODEL_WITH_TABLE.replace("max_constraints = 1", "max_constraints = 8"), "m.toml")
    with pytest.raises(ValueError, match=r"m.toml:14:19: `estimator.czf.max_constraints`: invalid setting"):
        too_many.estimator("czf")
    # The same value given as a keyword is the caller's: named as a setting, not at the file.
    with pytest.raises(ValueError, match=r"^invalid setting max_constraints = 8") as info:
        table.estimator("czf", max_constraints=8)
    assert "m.toml" not in str(info.value)
