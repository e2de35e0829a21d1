"""Fleet batch: filter many vehicles' logs, one task per log, on a Dask cluster or in this process.

A log is a Parquet file with the columns of ``port-est``'s CSV logs: ``k`` (consecutive integers),
``u1..up`` (the inputs ``u[k]``) and ``y1..ym`` (the measurement ``y[k+1]`` taken after the step;
the fuzzy-adaptive filter's logs add the receiver status, so ``m`` is the estimator's ``dim_z``).
Each log is filtered by ``Estimator.run`` (in Rust, the GIL released) and its estimates are written
as a Parquet file of the same name in ``out_dir``:

``k``
    ``k + 1`` of the input row: the row estimates ``x[k+1]``.
``xhat1..xhatn``, ``lo1..lon``, ``hi1..hin``, ``trace``
    The centre, the per-state bounds (one standard deviation, or the guaranteed interval; NaN for
    point estimates) and the trace of the shape matrix.
the estimator's own numbers
    ``tau1..tau3``, ``scale``, ``distance``, ``iterations`` (as ``Estimate.details``).
``status``, ``clean``
    How each step ended.

Each output is written to a temporary file beside it and renamed, so a reader never sees half a
file. A log is filtered in consecutive pieces (the same numbers as one run) and written piece by
piece (``DEFAULT_CHUNK_ROWS`` rows at a time), so a task's memory stays bounded whatever the length
of its log.

On a cluster::

    from dask.distributed import Client
    client = Client("tcp://scheduler-host:8786")     # the scheduler's address
    fleet.filter_logs(paths, "/shared/estimates", model=model, estimator="smf", client=client)

Every worker needs ``port_estimation`` (and pyarrow) installed, and the paths must be readable and
``out_dir`` writable from every worker (a shared file system). The model and the settings travel to
the workers by pickle. With ``client=None`` the logs are filtered one after another in this
process; the outputs are the same bit for bit.
"""

from __future__ import annotations

import os
import tempfile
import time
from pathlib import Path
from typing import Any, Iterable, Mapping, Sequence, Union

import numpy as np

from ._native import MAX_RUN_VALUES, Estimator, Model, ModelFile

__all__ = ["DEFAULT_CHUNK_ROWS", "filter_log", "filter_logs", "log_columns", "read_log", "write_log"]

PathLike = Union[str, "os.PathLike[str]"]

#: Rows per ``run`` call and per written piece unless ``chunk_rows`` says otherwise: 2^20 rows keep a
#: task's results near ``3 * 8 * 2^20 * n`` bytes (100 MB for n = 4) whatever the log's length.
DEFAULT_CHUNK_ROWS = 1 << 20


def log_columns(inputs: int, measurements: int) -> list[str]:
    """The column names of a log: ``k, u1..up, y1..ym``."""
    return ["k"] + [f"u{i + 1}" for i in range(inputs)] + [f"y{i + 1}" for i in range(measurements)]


def write_log(path: PathLike, k: np.ndarray, us: np.ndarray, ys: np.ndarray) -> None:
    """Writes a log (``k``, inputs ``(T, p)``, measurements ``(T, m)``) as Parquet, atomically."""
    import pyarrow as pa

    us, ys = np.asarray(us, dtype=float).reshape(len(k), -1), np.asarray(ys, dtype=float).reshape(len(k), -1)
    names = log_columns(us.shape[1], ys.shape[1])
    columns = [pa.array(np.asarray(k, dtype=np.int64))] + [pa.array(c) for c in us.T] + [pa.array(c) for c in ys.T]
    _write_atomically(Path(path), [pa.Table.from_arrays(columns, names=names)])


def read_log(path: PathLike, *, inputs: int, measurements: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Reads a log: returns ``k`` (int64, ``(T,)``), ``us`` ``(T, p)`` and ``ys`` ``(T, m)``.

    A null measurement cell is a sensor that did not report at that row: ``ys`` is then a
    ``numpy.ma`` masked array with those cells masked, which ``Estimator.run`` takes as partial
    measurements. Raises ValueError naming the file for a missing or unexpected column, a null
    ``k`` or input cell, or ``k`` that does not increase by one (the row is named).
    """
    import pyarrow.parquet as pq

    want = log_columns(inputs, measurements)
    schema = pq.read_schema(path)
    missing = [c for c in want if c not in schema.names]
    extra = [c for c in schema.names if c not in want]
    if missing or extra:
        raise ValueError(
            f"{path}: the log must have the columns {', '.join(want)}"
            + (f"; missing {', '.join(missing)}" if missing else "")
            + (f"; unexpected {', '.join(extra)}" if extra else "")
        )
    table = pq.read_table(path, columns=want)
    for name in want[: 1 + inputs]:
        if table.column(name).null_count:
            raise ValueError(f"{path}: column {name} has empty cells (only measurements may be missing)")
    k = table.column("k").to_numpy().astype(np.int64, copy=False)
    jumps = np.flatnonzero(np.diff(k) != 1)
    if len(jumps):
        row = int(jumps[0]) + 1
        raise ValueError(f"{path}: row {row}: k jumps from {k[row - 1]} to {k[row]} (k must increase by one)")

    def block(names: Sequence[str]) -> np.ndarray:
        if not names:
            return np.zeros((len(k), 0))
        return np.column_stack([table.column(n).to_numpy().astype(float, copy=False) for n in names])

    outputs = want[1 + inputs :]
    ys = block(outputs)
    if any(table.column(n).null_count for n in outputs):
        missing = np.column_stack([table.column(n).is_null().to_numpy(zero_copy_only=False) for n in outputs])
        ys = np.ma.masked_array(np.where(missing, 0.0, ys), mask=missing)
    return k, block(want[1 : 1 + inputs]), ys


def _write_atomically(path: Path, tables: Iterable[Any]) -> None:
    """Writes the tables (one schema) into one Parquet file at ``path`` through a renamed temporary."""
    import pyarrow.parquet as pq

    path.parent.mkdir(parents=True, exist_ok=True)
    fd, tmp = tempfile.mkstemp(dir=path.parent, prefix=f".{path.name}.", suffix=".tmp")
    os.close(fd)
    try:
        writer = None
        for table in tables:
            if writer is None:
                writer = pq.ParquetWriter(tmp, table.schema)
            writer.write_table(table)
        if writer is not None:
            writer.close()
        os.replace(tmp, path)
    except BaseException:
        Path(tmp).unlink(missing_ok=True)
        raise


def _estimates_table(k: np.ndarray, log, n: int):
    import pyarrow as pa

    columns, names = [pa.array(k + 1)], ["k"]
    for prefix, block in (("xhat", log.center), ("lo", log.lower), ("hi", log.upper)):
        for i in range(n):
            columns.append(pa.array(block[:, i]))
            names.append(f"{prefix}{i + 1}")
    columns.append(pa.array(log.trace))
    names.append("trace")
    for key, values in log.details.items():
        columns.append(pa.array(values))
        names.append(key)
    columns += [pa.array(log.status, type=pa.string()), pa.array(log.clean)]
    names += ["status", "clean"]
    return pa.Table.from_arrays(columns, names=names)


def _build(spec: Mapping[str, Any]) -> Estimator:
    model = spec["model"]
    if isinstance(model, ModelFile):
        return model.estimator(spec["estimator"], **spec["settings"])
    return Estimator(spec["estimator"], model, **spec["initial"], **spec["settings"])


def _filter_one(path: str, out_path: str, spec: Mapping[str, Any]) -> dict[str, Any]:
    """One task: filter the log at ``path`` into ``out_path``; returns its summary."""
    start = time.perf_counter()
    est = _build(spec)
    k, us, ys = read_log(path, inputs=est.dim_u, measurements=est.dim_z)
    chunk = spec["chunk_rows"] or max(1, min(DEFAULT_CHUNK_ROWS, MAX_RUN_VALUES // est.dim_x))
    counts = {"steps": 0, "unclean": 0}

    def pieces():
        for lo in range(0, len(k), chunk):
            hi = min(lo + chunk, len(k))
            log = est.run(us[lo:hi], ys[lo:hi])
            counts["steps"] += hi - lo
            counts["unclean"] += int(hi - lo - np.count_nonzero(log.clean))
            yield _estimates_table(k[lo:hi], log, est.dim_x)

    _write_atomically(Path(out_path), pieces())
    return {
        "log": path,
        "output": out_path,
        "steps": counts["steps"],
        "unclean": counts["unclean"],
        "seconds": time.perf_counter() - start,
    }


def filter_log(
    path: PathLike,
    out_path: PathLike,
    *,
    model: Union[Model, ModelFile],
    estimator: str,
    x0: Any = None,
    P0: Any = None,
    Q: Any = None,
    R: Any = None,
    settings: Mapping[str, Any] | None = None,
    chunk_rows: int | None = None,
) -> dict[str, Any]:
    """Filters one log into ``out_path`` (see the module); returns its summary
    (``log``, ``output``, ``steps``, ``unclean``, ``seconds``)."""
    spec = _spec(model, estimator, x0, P0, Q, R, settings, chunk_rows)
    path, out_path = os.path.abspath(os.fspath(path)), os.path.abspath(os.fspath(out_path))
    _refuse_overwriting_inputs([path], [out_path])
    return _filter_one(path, out_path, spec)


def _refuse_overwriting_inputs(paths: Sequence[str], outs: Sequence[str]) -> None:
    """Raises ValueError if an output would replace one of the logs: the same path, or the same file
    under another name (a link; compared by file identity, not by name)."""
    inputs = {os.path.normcase(os.path.realpath(p)): p for p in paths}
    for out in outs:
        same = inputs.get(os.path.normcase(os.path.realpath(out)))
        if same is None and os.path.exists(out):
            same = next((p for p in paths if os.path.exists(p) and os.path.samefile(p, out)), None)
        if same is not None:
            raise ValueError(f"the output {out} would overwrite the log {same}: choose another out_dir")


def _spec(model, estimator, x0, P0, Q, R, settings, chunk_rows) -> dict[str, Any]:
    if isinstance(model, (str, os.PathLike)):
        from ._native import read_model

        model = read_model(model)
    if not isinstance(model, (Model, ModelFile)):
        raise TypeError(f"model must be a Model, a ModelFile or a model file's path, not {type(model).__name__}")
    if chunk_rows is not None and (isinstance(chunk_rows, bool) or not isinstance(chunk_rows, int) or chunk_rows < 1):
        raise ValueError(f"chunk_rows must be a positive integer, got {chunk_rows!r}")
    initial = {key: value for key, value in (("x0", x0), ("P0", P0), ("Q", Q), ("R", R)) if value is not None}
    if isinstance(model, ModelFile) and initial:
        raise ValueError("a model file brings its own x0, p0, q, r: do not give x0, P0, Q or R with it")
    return {
        "model": model,
        "estimator": estimator,
        "initial": initial,
        "settings": dict(settings or {}),
        "chunk_rows": chunk_rows,
    }


def filter_logs(
    paths: Sequence[PathLike],
    out_dir: PathLike,
    *,
    model: Union[Model, ModelFile, PathLike],
    estimator: str,
    x0: Any = None,
    P0: Any = None,
    Q: Any = None,
    R: Any = None,
    settings: Mapping[str, Any] | None = None,
    client: Any = None,
    chunk_rows: int | None = None,
) -> list[dict[str, Any]]:
    """Filters every log of ``paths`` with the registry estimator ``estimator`` on ``model``, one
    task per log, writing ``out_dir/<log name>`` (Parquet; see the module for the columns).

    Parameters
    ----------
    paths : sequence of paths
        The logs (Parquet, columns ``k, u1..up, y1..ym``); their file names must differ.
    out_dir : path
        Where the estimates go (created if needed).
    model : Model, ModelFile or path
        The model; a ``port-est`` model file (or its path) also brings ``x0``, ``P0``, ``Q``, ``R``
        and the file's estimator settings.
    estimator : str
        A registry name (``estimators()``).
    x0, P0, Q, R : array_like, optional
        The initial estimate and noise (as for ``Estimator``), for a ``Model``.
    settings : dict, optional
        The estimator's settings (``solver``, ``horizon``...).
    client : dask.distributed.Client, optional
        Run on this cluster, one task per log; None filters the logs in this process, in order.
    chunk_rows : int, optional
        Rows per ``run`` call and per written piece (default ``DEFAULT_CHUNK_ROWS``, fewer if
        ``MAX_RUN_VALUES`` demands).

    Returns
    -------
    list of dict
        Per log, in the order of ``paths``: ``log``, ``output``, ``steps``, ``unclean`` (steps that did
        not end cleanly) and ``seconds`` (the task's wall time).

    Raises
    ------
    ValueError
        A malformed log (named), bad settings; the estimator's exceptions for a log it cannot filter.
    """
    spec = _spec(model, estimator, x0, P0, Q, R, settings, chunk_rows)
    # Absolute paths, resolved here on the client (a worker may run in another directory).
    paths = [os.path.abspath(os.fspath(p)) for p in paths]
    names = [Path(p).name for p in paths]
    if len(set(names)) != len(names):
        raise ValueError("the logs' file names must differ (each names its output in out_dir)")
    outs = [os.path.abspath(os.fspath(Path(out_dir) / name)) for name in names]
    _refuse_overwriting_inputs(paths, outs)
    _build(spec)  # settings errors here, once, rather than in every task
    if client is None:
        return [_filter_one(p, o, spec) for p, o in zip(paths, outs)]
    futures = client.map(_filter_one, paths, outs, spec=spec, pure=False)
    return client.gather(futures)
