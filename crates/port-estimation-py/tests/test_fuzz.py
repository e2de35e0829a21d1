"""Fuzzing of the entry points' argument types and shapes (hypothesis): NumPy dtypes, memory
orders, strides, masks, sizes and keyword values. Whatever is passed, a call either succeeds or
raises ``ValueError``/``TypeError`` (or, for a step, the estimation's own exceptions) and leaves the
estimator as it was; what it accepts, in any dtype or layout, gives exactly the numbers of the same
values as contiguous float64."""

from __future__ import annotations

import numpy as np
import pytest

import port_estimation as pe

hypothesis = pytest.importorskip("hypothesis")
import tempfile  # noqa: E402

from hypothesis.configuration import set_hypothesis_home_dir  # noqa: E402

# Hypothesis keeps caches in ./.hypothesis: a temporary directory instead, so that the test suite
# leaves nothing in the source tree.
set_hypothesis_home_dir(tempfile.mkdtemp(prefix="hypothesis-"))
from hypothesis import HealthCheck, given, settings  # noqa: E402
from hypothesis import strategies as st  # noqa: E402
from hypothesis.extra import numpy as hnp  # noqa: E402

FUZZ = settings(max_examples=100, deadline=None, database=None, suppress_health_check=[HealthCheck.too_slow])

A = np.array([[1.0, 0.1, 0.0], [0.0, 0.95, 0.1], [0.0, 0.0, 0.9]])
B = np.array([[0.0], [0.1], [0.05]])
C = np.array([[1.0, 0.0, 0.0], [0.0, 0.0, 1.0]])

DTYPES = [np.float64, np.float32, np.float16, np.int64, np.int8, np.uint16]
REFUSED_DTYPES = [np.bool_, np.complex128, np.object_, np.str_]


@st.composite
def arrays(draw, shapes, *, valid=False, maskable=False):
    """An array of the shapes: with ``valid``, real and finite in any real dtype, memory order or
    stride (masked too if ``maskable``); else of any dtype, sometimes with a non-finite entry or
    masked."""
    shape = draw(shapes)
    dtype = draw(st.sampled_from(DTYPES if valid else DTYPES + REFUSED_DTYPES))
    values = draw(hnp.arrays(np.float64, shape, elements=st.integers(-100, 100).map(lambda v: v / 4)))
    if not valid and values.size and draw(st.booleans()):
        values.flat[draw(st.integers(0, values.size - 1))] = draw(st.sampled_from([np.nan, np.inf, -np.inf]))
    if dtype is np.object_:
        a = values.astype(object)
    elif dtype is np.str_:
        a = values.astype(str)
    else:
        with np.errstate(all="ignore"):
            a = values.astype(dtype)
    layouts = ["c", "f", "strided"] + (["masked"] if maskable or not valid else [])
    layout = draw(st.sampled_from(layouts))
    if layout == "f":
        a = np.asfortranarray(a)
    elif layout == "strided" and a.ndim >= 1:
        a = np.repeat(a, 2, axis=-1)[..., ::2]
    elif layout == "masked":
        a = np.ma.masked_array(a, mask=draw(hnp.arrays(np.bool_, a.shape)))
    return a


ANY_SHAPE = hnp.array_shapes(min_dims=0, max_dims=3, min_side=0, max_side=4)


def _kf():
    kf = pe.KalmanFilter(pe.Model(A, B, C), P0=np.eye(3), Q=1e-2 * np.eye(3), R=0.1 * np.eye(2))
    kf.set_data_checks("off")  # the values are arbitrary: this is about their types and shapes
    return kf


def _state(est):
    e = est.estimate
    return est.x.copy(), est.P.copy(), e.status


def _same(est, state):
    x, p, status = state
    np.testing.assert_array_equal(est.x, x)
    np.testing.assert_array_equal(est.P, p)
    assert est.estimate.status == status


def _canonical(a) -> np.ndarray | None:
    """The float64 values a call that accepted ``a`` must have used (None: it must refuse it)."""
    if np.ma.isMaskedArray(a) or np.asarray(a).dtype.kind not in "iuf":
        return None
    return np.ascontiguousarray(np.asarray(a), dtype=np.float64)


U_SHAPES = st.sampled_from([(1,), (), (1, 1)])
Y_SHAPES = st.sampled_from([(2,), (2, 1), (1, 2)])


def _as_float(a):
    """``a``'s values as float64 (a masked array keeps its mask)."""
    if np.ma.isMaskedArray(a):
        return np.ma.masked_array(np.asarray(a.data, dtype=np.float64), mask=a.mask)
    return np.ascontiguousarray(a, dtype=np.float64)


@FUZZ
@given(u=arrays(U_SHAPES, valid=True), y=arrays(Y_SHAPES, valid=True, maskable=True))
def test_a_step_takes_real_arrays_in_any_dtype_and_layout_with_the_numbers_of_float64(u, y):
    e = _kf().step(u, y)
    expected = _kf().step(_as_float(u), _as_float(y) if np.ma.isMaskedArray(y) else _as_float(y).ravel())
    np.testing.assert_array_equal(e.center, expected.center)
    np.testing.assert_array_equal(e.shape, expected.shape)


@FUZZ
@given(u=arrays(ANY_SHAPE), y=arrays(ANY_SHAPE))
def test_a_step_refuses_what_it_cannot_take_and_changes_nothing(u, y):
    est = _kf()
    before = _state(est)
    try:
        est.step(u, y)
    except (ValueError, TypeError, pe.EstimationError):
        _same(est, before)
        return
    # Accepted: real, finite (where measured) and of the sizes.
    assert _canonical(u) is not None and np.isfinite(_canonical(u)).all() and np.size(u) == 1, u
    assert np.size(y) == 2 and np.asarray(y).dtype.kind in "iuf", y


@FUZZ
@given(
    us=arrays(st.sampled_from([(4, 1), (4,), (0, 1)]), valid=True),
    ys=arrays(st.just((4, 2)), valid=True, maskable=True),
)
def test_a_run_takes_real_tables_in_any_dtype_and_layout_with_the_numbers_of_float64(us, ys):
    rows = len(np.atleast_1d(us)) if np.ndim(us) else 1
    ys = ys[:rows]
    log = _kf().run(us, ys)
    expected = _kf().run(_as_float(us).reshape(rows, 1), _as_float(ys))
    np.testing.assert_array_equal(log.center, expected.center)
    np.testing.assert_array_equal(log.upper, expected.upper)
    assert log.status == expected.status


@FUZZ
@given(us=arrays(ANY_SHAPE), ys=arrays(ANY_SHAPE))
def test_a_run_refuses_what_it_cannot_take_and_changes_nothing(us, ys):
    est = _kf()
    before = _state(est)
    try:
        est.run(us, ys)
    except (ValueError, TypeError) as e:
        _same(est, before)
        assert getattr(e, "row", None) in (None, 0)
        return
    except pe.EstimationError as e:
        assert e.row is not None
        return
    assert _canonical(us) is not None and np.isfinite(_canonical(us)).all(), us


@FUZZ
@given(
    a=arrays(st.just((3, 3)), valid=True),
    b=arrays(st.just((3, 1)), valid=True),
    c=arrays(st.just((2, 3)), valid=True),
)
def test_a_model_takes_real_matrices_in_any_dtype_and_layout(a, b, c):
    model = pe.Model(a, b, c)
    for name, given_, shape in (("A", a, (3, 3)), ("B", b, (3, 1)), ("C", c, (2, 3))):
        np.testing.assert_array_equal(getattr(model, name), _as_float(given_).reshape(shape))


@FUZZ
@given(a=arrays(ANY_SHAPE), b=arrays(ANY_SHAPE), c=arrays(ANY_SHAPE))
def test_a_model_refuses_what_is_not_a_real_finite_matrix(a, b, c):
    try:
        pe.Model(a, b, c)
    except (ValueError, TypeError):
        return
    for given_ in (a, b, c):
        canonical = _canonical(given_)
        assert canonical is not None and np.isfinite(canonical).all(), given_


VALUES = st.one_of(
    st.none(),
    st.booleans(),
    st.integers(-(2**70), 2**70),
    st.floats(allow_nan=True),
    st.text(max_size=8),
    st.lists(st.integers(-3, 10**7), max_size=4),
)
KEYS = st.sampled_from(["horizon", "blocks", "max_sweeps", "tolerance", "lambda_v", "preset", "arrival", "theta", "bogus"])
# A small memory limit keeps what is built (and the test) small; the limit itself is tested in
# test_resources.py.
SMALL = {"memory_limit": 1 << 22}


@FUZZ
@given(kwargs=st.dictionaries(KEYS, VALUES, max_size=3))
def test_moving_horizon_keywords_of_any_type_are_checked_before_anything_is_built(kwargs):
    boxes = {"w_lower": -np.ones(3), "w_upper": np.ones(3), "v_lower": -np.ones(2), "v_upper": np.ones(2)}
    try:
        mhe = pe.MovingHorizonEstimator(pe.Model(A, B, C), R=0.1 * np.eye(2), **boxes, **SMALL, **kwargs)
    except (ValueError, TypeError, OverflowError):
        return
    # Built: within the memory limit, and it steps.
    mhe.step(np.zeros(1), np.zeros(2))


@FUZZ
@given(kwargs=st.dictionaries(st.sampled_from(["horizon", "max_iterations", "alpha"]), VALUES, max_size=2))
def test_nonlinear_mhe_keywords_of_any_type_are_checked_before_anything_is_built(kwargs):
    try:
        mhe = pe.NonlinearMHE(pe.Model.vessel(), **SMALL, **kwargs)
    except (ValueError, TypeError, OverflowError):
        return
    assert mhe.dim_x == 6
