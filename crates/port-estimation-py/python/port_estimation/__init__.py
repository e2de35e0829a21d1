"""Guaranteed (set-membership) and stochastic state estimation for port vehicles.

Every estimator of the Rust workspace's registry, over NumPy arrays: the Kalman, extended and
unscented Kalman filters, the certified set-membership filter and its reconstructions, the
robust and plain moving-horizon estimators, the nonlinear MHE and the fuzzy-adaptive Kalman
filter. A first estimate in four concepts, as in filterpy -- the sizes (from the model), the
attributes (``x0``, ``P0``, ``Q``, ``R``), ``predict`` and ``update``::

    import numpy as np
    import port_estimation as pe

    model = pe.Model(A=[[1.0, 0.1], [0.0, 1.0]], B=[[0.0], [0.1]], C=[[1.0, 0.0]])
    kf = pe.KalmanFilter(model, P0=1.0, Q=1e-4, R=1e-2)
    kf.predict(u=[1.0])
    e = kf.update(y=[0.05])        # e.center, e.shape, e.lower, e.upper, e.status
    smf = pe.SetMembershipFilter(model, P0=1.0, Q=1e-4, R=1e-2)
    log = smf.run(us, ys)          # a whole log in Rust: log.center (T, n), log.lower, log.upper

``estimators()`` lists every estimator with what it needs; ``Estimator(name, model, ...)`` builds
any of them. ``read_model(path)`` reads a ``port-est`` model file. ``read_bag(path, inputs,
outputs, ts=...)`` reads a ROS 2 bag (MCAP) into the arrays ``run`` takes, ``inspect_bag(path)``
lists its topics and fields. ``port_estimation.fleet`` filters many vehicles' Parquet logs on a
Dask cluster.

Errors: ``ValueError`` for bad input, refused before anything is done; ``EstimationError`` and its
subclasses ``NumericalError``, ``InconsistentDataError`` (with ``.step`` and ``.excess``) and
``RunError`` for what the estimation runs into; ``BagError`` (a ``ValueError``) for a bag that
cannot be read. After an exception from a single call the estimator's state is what it was
before; after one from ``run`` (``.row``) it holds the estimate after the row before ``.row``.
"""

from ._native import (
    MAX_RUN_VALUES,
    BagError,
    BagInfo,
    BagLog,
    EstimationError,
    Estimate,
    Estimator,
    ExtendedKalmanFilter,
    FuzzyKalmanFilter,
    InconsistentDataError,
    KalmanFilter,
    Model,
    ModelFile,
    MovingHorizonEstimator,
    NonlinearMHE,
    NumericalError,
    RunError,
    RunResult,
    SetMembershipFilter,
    UnscentedKalmanFilter,
    __version__,
    estimators,
    inspect_bag,
    parse_model,
    read_bag,
    read_model,
    solvers,
)

__all__ = [
    "MAX_RUN_VALUES",
    "BagError",
    "BagInfo",
    "BagLog",
    "EstimationError",
    "Estimate",
    "Estimator",
    "ExtendedKalmanFilter",
    "FuzzyKalmanFilter",
    "InconsistentDataError",
    "KalmanFilter",
    "Model",
    "ModelFile",
    "MovingHorizonEstimator",
    "NonlinearMHE",
    "NumericalError",
    "RunError",
    "RunResult",
    "SetMembershipFilter",
    "UnscentedKalmanFilter",
    "__version__",
    "estimators",
    "fleet",
    "inspect_bag",
    "parse_model",
    "read_bag",
    "read_model",
    "solvers",
]


def _restore_model(kind: str, args: tuple) -> Model:
    """Rebuilds a pickled ``Model`` from its recipe (the target of ``Model.__reduce__``)."""
    return Model._restore(kind, args)


def _restore_run_result(*tables) -> RunResult:
    """Rebuilds a pickled ``RunResult`` from its tables (the target of ``RunResult.__reduce__``)."""
    return RunResult._restore(*tables)


def __getattr__(name: str):
    # `fleet` needs pyarrow (and Dask for a cluster): imported on first use only.
    if name == "fleet":
        import importlib

        return importlib.import_module(".fleet", __name__)
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
