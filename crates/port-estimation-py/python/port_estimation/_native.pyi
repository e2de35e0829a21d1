"""Type stubs of the native module ``port_estimation._native`` (the Rust binding).

The documentation is in the docstrings of the module itself: ``help(port_estimation.KalmanFilter)``.
"""

from __future__ import annotations

import os
from typing import Any, Final, Literal, Mapping, Tuple, TypedDict, Union

import numpy as np
import numpy.typing as npt

ArrayLike = npt.ArrayLike
FloatArray = npt.NDArray[np.float64]
BoolArray = npt.NDArray[np.bool_]
IntArray = npt.NDArray[np.int64]
PathLike = Union[str, os.PathLike[str]]
Kind = Literal["gaussian", "guaranteed ellipsoid", "guaranteed constrained zonotope", "point"]
Capability = Literal["linear", "second-order", "differentiable", "discrete"]

MAX_RUN_VALUES: Final[int]
__version__: Final[str]

class EstimationError(Exception):
    row: int | None
    kind: str

class NumericalError(EstimationError): ...

class RunError(EstimationError):
    row: int

class BagError(ValueError):
    path: str
    rows_read: int
    offset: int | None
    topic: str | None
    key: str | None

class InconsistentDataError(EstimationError):
    step: int
    # The set-membership filter's proof: the separating distance; the moving-horizon window's:
    # how far V must widen, in widths (with the window's measured samples).
    excess: float
    samples: int
    # The Gaussian filters' innovation gate: NIS, its chi-squared threshold and probability.
    nis: float
    threshold: float
    probability: float
    # The output with the largest innovation in its own standard deviations, and that innovation.
    output: int | None
    residual: float | None

class Model:
    def __init__(
        self, A: ArrayLike, B: ArrayLike, C: ArrayLike, *, angles: dict[str, list[int]] | None = None
    ) -> None: ...
    @staticmethod
    def truck(ts: float = 0.001) -> Model: ...
    @staticmethod
    def vessel(ts: float = 0.1, rk4_substeps: int | None = None) -> Model: ...
    @staticmethod
    def carrier(speed: float = 6.0, load: int = 1, ts: float = 0.001) -> Model: ...
    @staticmethod
    def car(speed: float = 25.0, ts: float = 0.5) -> Model: ...
    @staticmethod
    def from_equations(text: str, file: str = "<string>") -> Model: ...
    @property
    def dims(self) -> tuple[int, int, int]: ...
    @property
    def capability(self) -> Capability: ...
    @property
    def description(self) -> str: ...
    @property
    def angles(self) -> dict[str, list[int]]: ...
    @property
    def A(self) -> FloatArray | None: ...
    @property
    def B(self) -> FloatArray | None: ...
    @property
    def C(self) -> FloatArray | None: ...
    def f(self, x: ArrayLike, u: ArrayLike | None = None) -> FloatArray: ...
    def h(self, x: ArrayLike, u: ArrayLike | None = None) -> FloatArray: ...
    def F(self, x: ArrayLike, u: ArrayLike | None = None) -> FloatArray: ...
    def H(self, x: ArrayLike, u: ArrayLike | None = None) -> FloatArray: ...
    @staticmethod
    def _restore(kind: str, args: tuple[Any, ...]) -> Model: ...
    def __reduce__(self) -> tuple[Any, tuple[Any, ...]]: ...

class ModelFile:
    def estimator(self, name: str = "smf", **settings: Any) -> Estimator: ...
    @property
    def model(self) -> Model: ...
    @property
    def x0(self) -> FloatArray: ...
    @property
    def P0(self) -> FloatArray: ...
    @property
    def Q(self) -> FloatArray: ...
    @property
    def R(self) -> FloatArray: ...
    @property
    def u_lower(self) -> FloatArray | None: ...
    @property
    def u_upper(self) -> FloatArray | None: ...
    @property
    def has_mhe(self) -> bool: ...
    @property
    def has_log(self) -> bool: ...
    @property
    def path(self) -> str: ...
    def read_bag(self, path: PathLike, *, start: float | None = None, start_ns: int | None = None) -> BagLog: ...
    def __reduce__(self) -> tuple[Any, tuple[Any, ...]]: ...

class Estimate:
    @property
    def kind(self) -> Kind: ...
    @property
    def center(self) -> FloatArray: ...
    @property
    def shape(self) -> FloatArray: ...
    @property
    def lower(self) -> FloatArray | None: ...
    @property
    def upper(self) -> FloatArray | None: ...
    @property
    def status(self) -> str: ...
    @property
    def clean(self) -> bool: ...
    @property
    def guaranteed(self) -> bool: ...
    @property
    def set(self) -> tuple[FloatArray, FloatArray, FloatArray, FloatArray] | None: ...
    @property
    def details(self) -> dict[str, float | None]: ...

class RunResult:
    @property
    def center(self) -> FloatArray: ...
    @property
    def lower(self) -> FloatArray: ...
    @property
    def upper(self) -> FloatArray: ...
    @property
    def trace(self) -> FloatArray: ...
    @property
    def status(self) -> list[str]: ...
    @property
    def clean(self) -> BoolArray: ...
    @property
    def details(self) -> dict[str, FloatArray]: ...
    @property
    def measured(self) -> BoolArray | None: ...
    @property
    def kind(self) -> Kind: ...
    def __len__(self) -> int: ...

class Estimator:
    def __init__(
        self,
        name: str,
        model: Model,
        *,
        x0: ArrayLike | None = None,
        P0: ArrayLike | None = None,
        Q: ArrayLike | None = None,
        R: ArrayLike | None = None,
        **settings: Any,
    ) -> None: ...
    def predict(self, u: ArrayLike | None = None, *, model: Model | None = None) -> Estimate: ...
    def update(self, y: ArrayLike, *, model: Model | None = None) -> Estimate: ...
    def step(
        self, u: ArrayLike | None, y: ArrayLike, *, measured: ArrayLike | None = None, model: Model | None = None
    ) -> Estimate: ...
    def run(
        self, us: ArrayLike | None, ys: ArrayLike, *, measured: ArrayLike | None = None, model: Model | None = None
    ) -> RunResult: ...
    def set_data_checks(
        self,
        policy: Literal["error", "flag", "restart", "off"] = "error",
        *,
        gate_probability: float | None = None,
    ) -> None: ...
    @property
    def x(self) -> FloatArray: ...
    @property
    def P(self) -> FloatArray: ...
    @property
    def estimate(self) -> Estimate: ...
    @property
    def Q(self) -> FloatArray: ...
    @property
    def R(self) -> FloatArray: ...
    @property
    def dim_x(self) -> int: ...
    @property
    def dim_u(self) -> int: ...
    @property
    def dim_z(self) -> int: ...
    @property
    def name(self) -> str: ...
    @property
    def kind(self) -> Kind: ...
    @property
    def model(self) -> Model: ...

class KalmanFilter(Estimator):
    def __init__(
        self,
        model: Model,
        *,
        x0: ArrayLike | None = None,
        P0: ArrayLike | None = None,
        Q: ArrayLike | None = None,
        R: ArrayLike | None = None,
    ) -> None: ...

class ExtendedKalmanFilter(Estimator):
    def __init__(
        self,
        model: Model,
        *,
        x0: ArrayLike | None = None,
        P0: ArrayLike | None = None,
        Q: ArrayLike | None = None,
        R: ArrayLike | None = None,
    ) -> None: ...

class UnscentedKalmanFilter(Estimator):
    def __init__(
        self,
        model: Model,
        *,
        x0: ArrayLike | None = None,
        P0: ArrayLike | None = None,
        Q: ArrayLike | None = None,
        R: ArrayLike | None = None,
        alpha: float | None = None,
        beta: float | None = None,
        kappa: float | None = None,
    ) -> None: ...

class SetMembershipFilter(Estimator):
    def __init__(
        self,
        model: Model,
        *,
        x0: ArrayLike | None = None,
        P0: ArrayLike | None = None,
        Q: ArrayLike | None = None,
        R: ArrayLike | None = None,
        solver: str | None = None,
        inconsistency: Literal["error", "flag", "restart"] | None = None,
        x_lower: ArrayLike | None = None,
        x_upper: ArrayLike | None = None,
        interval_observer: bool | None = None,
    ) -> None: ...

class MovingHorizonEstimator(Estimator):
    def __init__(
        self,
        model: Model,
        *,
        x0: ArrayLike | None = None,
        P0: ArrayLike | None = None,
        Q: ArrayLike | None = None,
        R: ArrayLike | None = None,
        robust: bool = True,
        **settings: Any,
    ) -> None: ...

class NonlinearMHE(Estimator):
    def __init__(
        self,
        model: Model,
        *,
        x0: ArrayLike | None = None,
        P0: ArrayLike | None = None,
        Q: ArrayLike | None = None,
        R: ArrayLike | None = None,
        **settings: Any,
    ) -> None: ...

class FuzzyKalmanFilter(Estimator):
    def __init__(
        self,
        model: Model,
        *,
        x0: ArrayLike | None = None,
        P0: ArrayLike | None = None,
        Q: ArrayLike | None = None,
        R: ArrayLike | None = None,
        fis: PathLike | None = None,
        horizontal: tuple[int, int] | None = None,
    ) -> None: ...

class EstimatorRow(TypedDict):
    name: str
    kind: Kind
    summary: str
    needs: Capability
    settings: str
    keywords: list[str]
    keyword_help: dict[str, str]
    extra_measurements: int
    details: dict[str, str]

def estimators() -> list[EstimatorRow]: ...
def solvers() -> list[str]: ...
def read_model(path: PathLike) -> ModelFile: ...
def parse_model(text: str, path: PathLike = "<string>") -> ModelFile: ...

# A model input or output from a topic's field: "topic:field" or (topic, field).
FieldSource = Union[str, Tuple[str, str]]

class BagLog:
    @property
    def u(self) -> FloatArray: ...
    @property
    def y(self) -> FloatArray: ...
    @property
    def measured(self) -> BoolArray: ...
    @property
    def t(self) -> FloatArray: ...
    @property
    def t_ns(self) -> IntArray: ...
    @property
    def k(self) -> IntArray: ...
    @property
    def inputs(self) -> list[str]: ...
    @property
    def outputs(self) -> list[str]: ...
    @property
    def header_stamped(self) -> dict[str, bool]: ...
    @property
    def path(self) -> str: ...
    def __len__(self) -> int: ...
    def __reduce__(self) -> tuple[Any, tuple[Any, ...]]: ...

class TopicRow(TypedDict):
    topic: str
    type: str
    message_encoding: str
    schema_encoding: str
    count: int
    rate_hz: float | None
    first: float | None
    last: float | None
    first_ns: int | None
    last_ns: int | None
    fields: list[str]
    fields_error: str | None

class BagInfo:
    @property
    def topics(self) -> list[TopicRow]: ...
    @property
    def error(self) -> str | None: ...
    @property
    def path(self) -> str: ...
    def __len__(self) -> int: ...

def read_bag(
    path: PathLike,
    inputs: Mapping[str, FieldSource] | None,
    outputs: Mapping[str, FieldSource] | None,
    *,
    ts: float | None = None,
    driving: str | None = None,
    stamps: Literal["log", "header"] = "log",
    start: float | None = None,
    start_ns: int | None = None,
    reorder_window: float | None = None,
) -> BagLog: ...
def inspect_bag(path: PathLike) -> BagInfo: ...
