"""Models (linear, vehicles, model files), pickling, the documentation and the type stubs."""

from __future__ import annotations

import ast
import inspect
import pickle
from pathlib import Path

import numpy as np
import pytest

import port_estimation as pe

ROOT = Path(__file__).resolve().parents[3]
EXAMPLE = ROOT / "examples" / "filter"
PACKAGE = Path(__file__).resolve().parents[1] / "python" / "port_estimation"


def test_vehicle_models_have_their_dimensions_and_capabilities():
    assert pe.Model.truck().dims == (3, 7, 3) and pe.Model.truck().capability == "second-order"
    assert pe.Model.vessel().dims == (6, 3, 3) and pe.Model.vessel().A is None
    assert pe.Model.carrier(load=2, speed=8.0).dims == (4, 8, 4)
    assert pe.Model.car().dims == (4, 1, 1) and pe.Model.car().capability == "linear"
    with pytest.raises(ValueError, match="containers"):
        pe.Model.carrier(load=3)
    with pytest.raises(ValueError, match="sampling period"):
        pe.Model.truck(ts=-1.0)


@pytest.mark.parametrize("model", [pe.Model.truck(), pe.Model.vessel(rk4_substeps=2)])
def test_jacobians_match_central_differences(model):
    n, p, _ = model.dims
    x = np.array([10.0, 0.2, 0.05]) if n == 3 else np.array([1.0, 2.0, 0.3, 1.0, 0.1, 0.01])
    u = np.r_[0.02, [19.5] * 6] if n == 3 else np.array([1e5, 2e4, 1e5])
    h = 1e-6
    for jac, fun in ((model.F, model.f), (model.H, model.h)):
        numeric = np.column_stack([(fun(x + h * e, u) - fun(x - h * e, u)) / (2 * h) for e in np.eye(n)])
        np.testing.assert_allclose(jac(x, u), numeric, rtol=1e-5, atol=1e-6)


def test_linear_model_evaluates_its_matrices():
    a, b, c = np.array([[1.0, 0.1], [0.0, 1.0]]), np.array([[0.0], [0.1]]), np.array([[1.0, 0.0]])
    m = pe.Model(a, b, c)
    np.testing.assert_array_equal(m.f([1.0, 2.0], [3.0]), a @ [1.0, 2.0] + b @ [3.0])
    np.testing.assert_array_equal(m.h([1.0, 2.0]), [1.0])
    np.testing.assert_array_equal(m.F([0.0, 0.0]), a)
    np.testing.assert_array_equal(m.C, c)


@pytest.mark.parametrize(
    "model",
    [pe.Model([[0.9]], [[1.0]], [[1.0]]), pe.Model.truck(), pe.Model.vessel(), pe.Model.carrier(load=0), pe.Model.car()],
)
def test_models_pickle_by_their_recipe(model):
    again = pickle.loads(pickle.dumps(model))
    assert repr(again) == repr(model)
    n, p, _ = model.dims
    x, u = np.linspace(1, 2, n), np.linspace(0.01, 0.02, p)
    if n == 3:
        x, u = np.array([10.0, 0.1, 0.0]), np.r_[0.01, [19.5] * 6]
    np.testing.assert_array_equal(again.f(x, u), model.f(x, u))


def test_a_model_file_builds_every_estimator_it_can_as_port_est_does():
    mf = pe.read_model(EXAMPLE / "model.toml")
    assert mf.model.dims == (2, 1, 1) and mf.has_mhe
    np.testing.assert_array_equal(mf.u_lower, [-1.0])
    data = np.loadtxt(EXAMPLE / "data.csv", delimiter=",", skiprows=1)
    us, ys = data[:, 1:2], data[:, 2:3]
    for row in pe.estimators():
        if row["extra_measurements"]:
            continue
        est = mf.estimator(row["name"])
        log = est.run(us, ys)
        assert log.kind == row["kind"] and len(log) == len(us)
        # The row declares the numbers every step reports, in order, each with its meaning.
        assert list(log.details) == list(row["details"]) == list(est.estimate.details)
        assert all(row["details"].values())
    # The default is the set-membership filter, as for `port-est filter`.
    assert mf.estimator().name == "smf"
    smf = mf.estimator("smf", solver="faer-ipm")
    assert smf.step(us[0], ys[0]).kind == "guaranteed ellipsoid"
    again = pickle.loads(pickle.dumps(mf))
    np.testing.assert_array_equal(again.estimator("kf").run(us, ys).center, mf.estimator("kf").run(us, ys).center)


def test_model_file_errors_name_the_line_and_column():
    text = (EXAMPLE / "model.toml").read_text()
    with pytest.raises(ValueError, match=r"m\.toml:8:\d+: `q`"):
        pe.parse_model(text.replace("q  = [[1e-6, 0.0], [0.0, 1e-4]]", "q  = [[-1e-6, 0.0], [0.0, 1e-4]]"), "m.toml").estimator(
            "kf"
        )
    with pytest.raises(ValueError, match=r"m\.toml:\d+:\d+: .*`b`"):
        pe.parse_model(text.replace("b  = [[0.0], [0.01]]", "b  = [[0.0]]"), "m.toml")
    with pytest.raises(ValueError, match="nope.toml"):
        pe.read_model(EXAMPLE / "nope.toml")


def test_a_model_per_call_is_a_time_varying_model():
    a1, a2 = np.array([[0.9, 0.1], [0.0, 0.8]]), np.array([[0.5, 0.0], [0.2, 0.7]])
    b, c = np.array([[0.0], [1.0]]), np.array([[1.0, 0.0]])
    m1, m2 = pe.Model(a1, b, c), pe.Model(a2, b, c)
    switching = pe.KalmanFilter(m1, Q=0.01, R=0.1)
    fixed = pe.KalmanFilter(m2, Q=0.01, R=0.1)
    for k in range(5):
        e = switching.step([1.0], [0.3 * k], model=m2)
        f = fixed.step([1.0], [0.3 * k])
    np.testing.assert_array_equal(e.center, f.center)


def test_every_listed_keyword_is_read_and_no_other():
    """The registry's keyword list (one per kind of settings) is what the keyword parser reads: a
    listed keyword with a value of the wrong type is refused as that value, never as unknown."""
    mf = pe.read_model(EXAMPLE / "model.toml")
    for row in pe.estimators():
        assert list(row["keyword_help"]) == row["keywords"] and all(row["keyword_help"].values())
        for keyword in row["keywords"]:
            with pytest.raises(ValueError) as info:
                mf.estimator(row["name"], **{keyword: object()})
            assert "unknown setting" not in str(info.value), (row["name"], keyword, str(info.value))
        with pytest.raises(ValueError, match="unknown setting") as info:
            mf.estimator(row["name"], not_a_setting=1.0)
        assert ", ".join(row["keywords"]) in str(info.value) or not row["keywords"]


def test_the_registry_is_listed_with_its_keywords():
    rows = {r["name"]: r for r in pe.estimators()}
    assert {"kf", "ekf", "ukf", "smf", "yang-li", "yang-li-with-input", "rmhe", "mhe", "mhe-ukf", "fkf"} <= set(rows)
    assert "solver" in rows["smf"]["keywords"] and rows["kf"]["keywords"] == []
    assert rows["fkf"]["extra_measurements"] == 2
    assert pe.solvers()[0] == "two-multiplier"


def test_help_reads_like_filterpy():
    doc = pe.KalmanFilter.__doc__
    for section in ("Parameters", "Attributes", "Examples", "x0", "P0"):
        assert section in doc
    assert list(inspect.signature(pe.KalmanFilter).parameters)[:5] == ["model", "x0", "P0", "Q", "R"]
    assert "alpha" in inspect.signature(pe.UnscentedKalmanFilter).parameters
    for cls in (pe.Estimator, pe.SetMembershipFilter, pe.Model, pe.Estimate, pe.RunResult):
        assert cls.__doc__ and len(cls.__doc__) > 200, cls
    for method in (pe.Estimator.predict, pe.Estimator.update, pe.Estimator.step, pe.Estimator.run):
        assert method.__doc__


def _defined(body: list[ast.stmt]) -> set[str]:
    """The functions and annotated names a stub body defines."""
    out = set()
    for node in body:
        if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef, ast.ClassDef)):
            out.add(node.name)
        elif isinstance(node, ast.AnnAssign) and isinstance(node.target, ast.Name):
            out.add(node.target.id)
    return out


def _stub_names(tree: ast.Module) -> dict[str, set[str]]:
    return {
        name: _defined(node.body) if isinstance(node, ast.ClassDef) else set()
        for node in tree.body
        for name in _defined([node])
    }


def test_the_type_stubs_cover_the_native_module():
    stubs = _stub_names(ast.parse((PACKAGE / "_native.pyi").read_text()))
    native = pe._native
    public = [n for n in dir(native) if not n.startswith("_") or n == "__version__"]
    missing = [n for n in public if n not in stubs]
    assert not missing, f"not in _native.pyi: {missing}"
    for name in public:
        obj = getattr(native, name)
        if isinstance(obj, type) and not issubclass(obj, BaseException):
            own = {a for a in vars(obj) if not a.startswith("_") or a in ("__len__",)}
            assert own <= stubs[name], f"{name}: {own - stubs[name]} not in the stub"
    assert (PACKAGE / "py.typed").exists()


# Each convenience class is `Estimator(<registry name>, ...)` with that row's settings as keywords.
ALIASES = {
    "KalmanFilter": "kf",
    "ExtendedKalmanFilter": "ekf",
    "UnscentedKalmanFilter": "ukf",
    "SetMembershipFilter": "smf",
    "MovingHorizonEstimator": "rmhe",
    "NonlinearMHE": "mhe-ukf",
    "FuzzyKalmanFilter": "fkf",
}


def test_the_convenience_classes_take_their_rows_keywords_and_match_their_stubs():
    rows = {r["name"]: r for r in pe.estimators()}
    tree = ast.parse((PACKAGE / "_native.pyi").read_text())
    stub_init = {
        node.name: [a.arg for a in (f.args.args + f.args.kwonlyargs)][1:] + ([f.args.kwarg.arg] if f.args.kwarg else [])
        for node in tree.body
        if isinstance(node, ast.ClassDef)
        for f in node.body
        if isinstance(f, ast.FunctionDef) and f.name == "__init__"
    }
    subclasses = {c.__name__ for c in pe.Estimator.__subclasses__()}
    assert subclasses == set(ALIASES), "a convenience class without its registry row here (or the reverse)"
    for cls_name, name in ALIASES.items():
        params = inspect.signature(getattr(pe, cls_name)).parameters
        runtime = list(params)
        assert stub_init[cls_name] == runtime, f"{cls_name}: the stub's __init__ {stub_init[cls_name]} != {runtime}"
        own = [p for p in runtime[5:] if params[p].kind != inspect.Parameter.VAR_KEYWORD]
        # `robust` chooses between the robust and the plain moving-horizon rows, which share settings.
        unknown = set(own) - set(rows[name]["keywords"]) - {"robust"}
        assert runtime[:5] == ["model", "x0", "P0", "Q", "R"] and not unknown, f"{cls_name}: {unknown}"
        assert f'Estimator("{name}"' in getattr(pe, cls_name).__doc__, cls_name


def test_the_readme_examples_run(tmp_path, monkeypatch):
    """The Python examples of the workspace's README and of this package's (not the cluster one)."""
    # In a directory of their own (nothing written into the tree), with the examples they read.
    monkeypatch.chdir(tmp_path)
    (tmp_path / "examples").symlink_to(ROOT / "examples")
    (tmp_path / "crates").symlink_to(ROOT / "crates")  # the bag example reads a test bag
    for readme in (ROOT / "README.md", PACKAGE.parents[1] / "README.md"):
        blocks = readme.read_text().split("```python\n")[1:]
        ran = 0
        for block in blocks:
            code = block.split("```", 1)[0]
            if "Client(" in code:
                continue
            exec(compile(code, str(readme), "exec"), {})
            ran += 1
        assert ran, readme
