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

A log may also be a ROS 2 bag (a ``.mcap`` file), read through a mapping and filtered as a Parquet log's rows
would be (its estimates go to ``<name>.parquet``). The mapping is the ``[log]`` table of the model file when
``model`` is a ``ModelFile`` that has one (as ``ModelFile.read_bag`` and ``port-est`` read it), or ``bag=``:
``read_bag``'s keywords (``dict(inputs=..., outputs=..., ts=...)``) or a ``ModelFile`` whose ``[log]`` table maps
the bags; ``bag=`` wins over the model file's table. A bag is read whole into its arrays (``T × (p + 2m)`` numbers)
before it is filtered in pieces; the bag itself is memory-mapped, not read into memory.

Each output is written to a temporary file beside it and renamed, so a reader never sees half a
file. A log is read, filtered and written in consecutive pieces (``DEFAULT_CHUNK_ROWS`` rows at a
time, the same numbers as one run), so a task's memory stays bounded whatever the length of its
log (by the piece and by the log's Parquet row groups: ``write_log`` writes groups of
``ROW_GROUP_ROWS``).

``filter_logs`` filters every log whatever happens to the others and returns one summary per log:
``status`` ``"ok"``, or ``"error"`` with ``error`` (the exception's type and message, naming the
log) and ``row`` (the log's row, counted from 0 over the whole log, where a step failed). A log
that fails leaves no output: a temporary file is removed, and an output of the same name left by
an earlier run is removed too, so that ``out_dir`` holds the current outputs only. ``filter_log``
raises instead, with ``.log`` and ``.row`` set on the exception.

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

from ._native import MAX_RUN_VALUES, Estimator, Model, ModelFile, read_bag

__all__ = [
    "DEFAULT_CHUNK_ROWS",
    "ROW_GROUP_ROWS",
    "filter_log",
    "filter_logs",
    "log_columns",
    "read_log",
    "write_log",
]

PathLike = Union[str, "os.PathLike[str]"]

#: Rows per ``run`` call and per piece read and written unless ``chunk_rows`` says otherwise: 2^13
#: rows keep a task's tables near ``8 * 2^13 * (3n + p + m + 4)`` bytes (4 MB for the straddle
#: carrier) whatever the log's length. Measured on a 4·10⁶-row carrier log: a peak of 150 MB for
#: the whole process (65 MB of it the interpreter and the libraries), against 200 MB with 2^16
#: rows, and no slower.
DEFAULT_CHUNK_ROWS = 1 << 13

#: Rows per Parquet row group written by ``write_log`` (a reader decodes a group at a time).
ROW_GROUP_ROWS = 1 << 16


def log_columns(inputs: int, measurements: int) -> list[str]:
    """The column names of a log: ``k, u1..up, y1..ym``."""
    return ["k"] + [f"u{i + 1}" for i in range(inputs)] + [f"y{i + 1}" for i in range(measurements)]


def write_log(path: PathLike, k: np.ndarray, us: np.ndarray, ys: np.ndarray) -> None:
    """Writes a log (``k``, inputs ``(T, p)``, measurements ``(T, m)``) as Parquet, atomically."""
    import pyarrow as pa

    us, ys = np.asarray(us, dtype=float), np.asarray(ys, dtype=float)
    us, ys = (a[:, None] if a.ndim == 1 else a.reshape(len(k), a.shape[-1]) for a in (us, ys))
    names = log_columns(us.shape[1], ys.shape[1])
    columns = [pa.array(np.asarray(k, dtype=np.int64))] + [pa.array(c) for c in us.T] + [pa.array(c) for c in ys.T]
    _write_atomically(Path(path), [pa.Table.from_arrays(columns, names=names)], row_group_size=ROW_GROUP_ROWS)


def read_log(path: PathLike, *, inputs: int, measurements: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Reads a log: returns ``k`` (int64, ``(T,)``), ``us`` ``(T, p)`` and ``ys`` ``(T, m)``.

    A null measurement cell is a sensor that did not report at that row: ``ys`` is then a
    ``numpy.ma`` masked array with those cells masked, which ``Estimator.run`` takes as partial
    measurements. Raises ValueError naming the file for a missing or unexpected column, a null
    ``k`` or input cell, or ``k`` that does not increase by one (the row is named).
    """
    import pyarrow.parquet as pq

    _checked_columns(path, pq.read_schema(path).names, inputs, measurements)
    return _piece(path, pq.read_table(path, columns=log_columns(inputs, measurements)), inputs, measurements)


def _checked_columns(path: PathLike, names: Sequence[str], inputs: int, measurements: int) -> list[str]:
    """The log's columns ``k, u1..up, y1..ym``, or ValueError naming the file and what differs."""
    want = log_columns(inputs, measurements)
    missing = [c for c in want if c not in names]
    extra = [c for c in names if c not in want]
    if missing or extra:
        raise ValueError(
            f"{path}: the log must have the columns {', '.join(want)}"
            + (f"; missing {', '.join(missing)}" if missing else "")
            + (f"; unexpected {', '.join(extra)}" if extra else "")
        )
    return want


def _piece(path: PathLike, table: Any, inputs: int, measurements: int, first: int = 0, k_before: int | None = None):
    """``k``, ``us``, ``ys`` of a piece of a log (a table or record batch whose first row is the
    log's row ``first``; ``k_before`` is the ``k`` of the row before it), checked as ``read_log``
    says."""
    want = log_columns(inputs, measurements)
    for name in want[: 1 + inputs]:
        if table.column(name).null_count:
            raise ValueError(f"{path}: column {name} has empty cells (only measurements may be missing)")
    k = table.column("k").to_numpy().astype(np.int64, copy=False)
    steps = np.diff(k) if k_before is None else np.diff(np.r_[k_before, k])
    jumps = np.flatnonzero(steps != 1)
    if len(jumps):
        row = int(jumps[0]) + (1 if k_before is None else 0)
        before = k[row - 1] if row > 0 else k_before
        e = ValueError(f"{path}: row {first + row}: k jumps from {before} to {k[row]} (k must increase by one)")
        e.row = first + row
        raise e

    def block(columns: Sequence[str]) -> np.ndarray:
        if not columns:
            return np.zeros((len(k), 0))
        return np.column_stack([table.column(n).to_numpy(zero_copy_only=False).astype(float, copy=False) for n in columns])

    outputs = want[1 + inputs :]
    ys = block(outputs)
    if any(table.column(n).null_count for n in outputs):
        missing = np.column_stack([table.column(n).is_null().to_numpy(zero_copy_only=False) for n in outputs])
        ys = np.ma.masked_array(np.where(missing, 0.0, ys), mask=missing)
    return k, block(want[1 : 1 + inputs]), ys


def _write_atomically(
    path: Path, tables: Iterable[Any], row_group_size: int | None = None, dictionary: Sequence[str] = ()
) -> None:
    """Writes the tables (one schema, at least one table) into one Parquet file at ``path`` through
    a renamed temporary; nothing is left behind if a table fails. Only the columns ``dictionary``
    are dictionary-encoded: trying it on float columns (pyarrow's default) took 80 % of the time
    of writing an estimates file, for a larger file."""
    import pyarrow.parquet as pq

    path.parent.mkdir(parents=True, exist_ok=True)
    fd, tmp = tempfile.mkstemp(dir=path.parent, prefix=f".{path.name}.", suffix=".tmp")
    os.close(fd)
    writer = None
    try:
        for table in tables:
            if writer is None:
                writer = pq.ParquetWriter(tmp, table.schema, use_dictionary=list(dictionary))
            writer.write_table(table, row_group_size=row_group_size)
        if writer is None:
            raise ValueError(f"{path}: nothing to write")
        writer.close()
        writer = None
        os.replace(tmp, path)
    except BaseException:
        if writer is not None:
            writer.close()
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
    """One task: filter the log at ``path`` into ``out_path``, streaming it piece by piece; returns
    its summary. Raises the first exception, with ``.log`` and ``.row`` (the log's row) set and its
    message naming both; nothing is left at ``out_path`` then (not even an earlier run's output)."""
    import pyarrow.parquet as pq

    start = time.perf_counter()
    counts = {"steps": 0, "unclean": 0}
    try:
        est = _build(spec)
        chunk = spec["chunk_rows"] or max(1, min(DEFAULT_CHUNK_ROWS, MAX_RUN_VALUES // est.dim_x))
        if _is_bag(path):
            batches = _bag_pieces(path, spec, est, chunk)
        else:
            reader = pq.ParquetFile(path, pre_buffer=False)
            want = _checked_columns(path, reader.schema_arrow.names, est.dim_u, est.dim_z)
            batches = reader.iter_batches(batch_size=chunk, columns=want)

        def pieces():
            k_before = None
            for batch in batches:
                first = counts["steps"]
                if isinstance(batch, tuple):
                    k, us, ys = batch
                else:
                    k, us, ys = _piece(path, batch, est.dim_u, est.dim_z, first, k_before)
                try:
                    log = est.run(us, ys)
                except Exception as e:
                    row = getattr(e, "row", None)
                    if row is not None:
                        # The log's row, not the piece's.
                        e.row = first + row
                        message = str(e)
                        prefix = f"row {row}: "
                        e.args = (f"row {e.row}: " + (message[len(prefix) :] if message.startswith(prefix) else message),)
                    raise
                counts["steps"] += len(k)
                counts["unclean"] += int(len(k) - np.count_nonzero(log.clean))
                k_before = int(k[-1]) if len(k) else k_before
                yield _estimates_table(k, log, est.dim_x)
            if counts["steps"] == 0:
                # A log without rows: an output without rows, with the columns.
                empty = np.zeros((0, est.dim_u)), np.zeros((0, est.dim_z))
                yield _estimates_table(np.zeros(0, dtype=np.int64), est.run(*empty), est.dim_x)

        _write_atomically(Path(out_path), pieces(), dictionary=["status"])
    except Exception as e:
        Path(out_path).unlink(missing_ok=True)
        _name_the_log(e, path)
        raise
    return {
        "log": path,
        "output": out_path,
        "status": "ok",
        "steps": counts["steps"],
        "unclean": counts["unclean"],
        "seconds": time.perf_counter() - start,
    }


def _is_bag(path: PathLike) -> bool:
    return os.fspath(path).lower().endswith(".mcap")


def _output_name(path: PathLike) -> str:
    """A log's output file name: the log's, a bag's with ``.parquet`` for ``.mcap``."""
    p = Path(path)
    return p.stem + ".parquet" if _is_bag(p) else p.name


def _bag_pieces(path: str, spec: Mapping[str, Any], est: Estimator, chunk: int):
    """``k``, ``us``, ``ys`` (masked where not measured) of a bag read through ``spec["bag"]``, in
    pieces of ``chunk`` rows."""
    source, model = spec["bag"], spec["model"]
    if isinstance(source, ModelFile):
        log = source.read_bag(path)
    elif source:
        log = read_bag(path, **source)
    elif isinstance(model, ModelFile) and model.has_log:
        log = model.read_bag(path)
    else:
        raise ValueError(
            f"{path}: a ROS 2 bag needs a mapping: a model file with a [log] table, or "
            "bag=dict(inputs=..., outputs=..., ts=... or driving=...)"
        )
    if len(log.inputs) != est.dim_u or len(log.outputs) != est.dim_z:
        raise ValueError(
            f"{path}: bag= maps {len(log.inputs)} inputs and {len(log.outputs)} outputs; "
            f"the estimator takes {est.dim_u} and {est.dim_z}"
        )
    for i in range(0, len(log), chunk):
        j = min(i + chunk, len(log))
        mask = ~log.measured[i:j]
        yield log.k[i:j], log.u[i:j], np.ma.masked_array(np.where(mask, 0.0, log.y[i:j]), mask=mask)


def _name_the_log(e: BaseException, path: str) -> None:
    """Sets ``.log`` (and ``.row``, None if the exception has none) on ``e``, and starts its
    message with the log's path."""
    e.log = path
    if not hasattr(e, "row"):
        e.row = None
    message = str(e)
    if not message.startswith(str(path)):
        e.args = (f"{path}: {message}",)


def _summarise_failure(path: str, out_path: str, spec: Mapping[str, Any]) -> dict[str, Any]:
    """One task of ``filter_logs``: ``_filter_one``, its exception turned into an error summary."""
    start = time.perf_counter()
    try:
        return _filter_one(path, out_path, spec)
    except Exception as e:
        return {
            "log": path,
            "output": None,
            "status": "error",
            "error": f"{type(e).__name__}: {e}",
            "row": getattr(e, "row", None),
            "steps": None,
            "unclean": None,
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
    bag: Mapping[str, Any] | ModelFile | PathLike | None = None,
) -> dict[str, Any]:
    """Filters one log into ``out_path`` (see the module); returns its summary
    (``log``, ``output``, ``status``, ``steps``, ``unclean``, ``seconds``). A log that cannot be
    filtered raises (ValueError for a malformed log, the estimator's exceptions for a step), with
    ``.log`` and ``.row`` (the log's row) set, and leaves nothing at ``out_path``."""
    spec = _spec(model, estimator, x0, P0, Q, R, settings, chunk_rows, bag)
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


def _spec(model, estimator, x0, P0, Q, R, settings, chunk_rows, bag=None) -> dict[str, Any]:
    if isinstance(model, (str, os.PathLike)):
        from ._native import read_model

        model = read_model(model)
    if not isinstance(model, (Model, ModelFile)):
        raise TypeError(f"model must be a Model, a ModelFile or a model file's path, not {type(model).__name__}")
    if chunk_rows is not None and (isinstance(chunk_rows, bool) or not isinstance(chunk_rows, int) or chunk_rows < 1):
        raise ValueError(f"chunk_rows must be a positive integer, got {chunk_rows!r}")
    if isinstance(bag, (str, os.PathLike)):
        from ._native import read_model

        bag = read_model(bag)
    if isinstance(bag, ModelFile) and not bag.has_log:
        raise ValueError(f"bag={bag.path}: the model file has no [log] table mapping a bag's topics")
    if bag is not None and not isinstance(bag, (ModelFile, Mapping)):
        raise TypeError(f"bag must be read_bag's keywords (a dict) or a ModelFile, not {type(bag).__name__}")
    initial = {key: value for key, value in (("x0", x0), ("P0", P0), ("Q", Q), ("R", R)) if value is not None}
    if isinstance(model, ModelFile) and initial:
        raise ValueError("a model file brings its own x0, p0, q, r: do not give x0, P0, Q or R with it")
    return {
        "model": model,
        "estimator": estimator,
        "initial": initial,
        "settings": dict(settings or {}),
        "chunk_rows": chunk_rows,
        "bag": bag if isinstance(bag, ModelFile) else dict(bag or {}),
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
    bag: Mapping[str, Any] | ModelFile | PathLike | None = None,
) -> list[dict[str, Any]]:
    """Filters every log of ``paths`` with the registry estimator ``estimator`` on ``model``, one
    task per log, writing ``out_dir/<log name>`` (Parquet; see the module for the columns).

    Parameters
    ----------
    paths : sequence of paths
        The logs (Parquet, columns ``k, u1..up, y1..ym``, or ROS 2 bags with ``bag``); their output
        names must differ.
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
    bag : dict, ModelFile or path, optional
        For logs that are ROS 2 bags (``.mcap``): ``read_bag``'s keywords (``inputs``, ``outputs``,
        ``ts`` or ``driving``, ...), or a model file (or its path) whose ``[log]`` table maps them;
        without it, the ``[log]`` table of ``model`` when it is a model file that has one. Their
        estimates go to ``<name>.parquet``.

    Returns
    -------
    list of dict
        Per log, in the order of ``paths``: ``log``, ``output``, ``status`` (``"ok"`` or
        ``"error"``), ``steps`` and ``unclean`` (steps that did not end cleanly), ``seconds`` (the
        task's wall time); for an error, ``error`` (the exception's type and message, naming the
        log) and ``row`` (the log's row where a step failed, or None), with ``output``, ``steps``
        and ``unclean`` None. Every log is filtered whatever happens to the others.

    Raises
    ------
    ValueError
        Bad settings or paths (an output that would replace a log, file names that repeat), before
        any log is read.
    """
    spec = _spec(model, estimator, x0, P0, Q, R, settings, chunk_rows, bag)
    # Absolute paths, resolved here on the client (a worker may run in another directory).
    paths = [os.path.abspath(os.fspath(p)) for p in paths]
    names = [_output_name(p) for p in paths]
    if len(set(names)) != len(names):
        raise ValueError("the logs' file names must differ (each names its output in out_dir)")
    outs = [os.path.abspath(os.fspath(Path(out_dir) / name)) for name in names]
    _refuse_overwriting_inputs(paths, outs)
    _build(spec)  # settings errors here, once, rather than in every task
    if client is None:
        return [_summarise_failure(p, o, spec) for p, o in zip(paths, outs)]
    futures = client.map(_summarise_failure, paths, outs, spec=spec, pure=False)
    return client.gather(futures)
