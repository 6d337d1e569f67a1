"""Run a sweep: chunks of flights on local processes (default), a Dask LocalCluster
(``workers``) or an existing Dask cluster (``scheduler``); results stored per chunk, so a killed
run resumes where it stopped.

The result of a chunk depends on the chunk alone (fixed flights, seeded values, independent
lanes), never on where or when it ran: every backend and every resumed run gives the same
bits.
"""
from collections.abc import Callable, Sequence
from concurrent.futures import ProcessPoolExecutor, as_completed
import json
import multiprocessing
import os
from pathlib import Path
import sys
import time
from typing import Any

import numpy as np
from numpy.typing import NDArray

from quadcog import validate
from quadcog.errors import QuadcogError, SchedulerError, SizeError
from quadcog.files import atomic_write, check_outputs, one_line
from quadcog.interrupts import children_without_sigint, die_with_parent
from quadcog.sweeps.arrow_table import require_pyarrow, to_arrow
from quadcog.sweeps.flights import make_job, run_chunk
from quadcog.sweeps.integrity import LOCK_NAME, SweepLock, chunk_metadata, columns_of_table, verify_chunk
from quadcog.sweeps.scheduler import probe_scheduler
from quadcog.sweeps.spec import Sweep, SweepError, from_dict, load_sweep
from quadcog.viz.progress import ProgressCounter

__all__ = ["CHUNK_FOLDER", "MANIFEST", "ChunkStore", "SweepResult", "sweep",
           "run_cli", "output_names"]

CHUNK_FOLDER = "chunks"
MANIFEST = "sweep.json"
MAX_WORKERS = 256           # processes: more than any machine this runs on gives a benefit


class ChunkStore:
    """``out/sweep.json`` (the sweep's fingerprint) and ``out/chunks/chunk-NNNNN.parquet``,
    each written to a temporary name and renamed, so a chunk file is complete or absent; each
    chunk records which sweep, chunk and flights it holds, its row count and a checksum
    (``quadcog.sweeps.integrity``), checked before a resumed sweep uses it.

    Parameters
    ----------
    out : str or os.PathLike
        The results folder (created if needed).
    sweep : quadcog.sweeps.spec.Sweep
        The sweep whose chunks it stores.

    Raises
    ------
    quadcog.errors.SweepError
        When ``out`` holds the results of a different sweep.
    """

    def __init__(self, out: str | os.PathLike[str], sweep: Sweep) -> None:
        self.out = Path(out)
        self.folder = self.out / CHUNK_FOLDER
        self.fingerprint = sweep.fingerprint()
        manifest = self.out / MANIFEST
        if manifest.is_file():
            try:
                old = json.loads(manifest.read_text()).get("fingerprint")
            except (ValueError, OSError, AttributeError):
                old = None
            if old != self.fingerprint:
                raise SweepError(f"{self.out}: holds the results of a different sweep (or of "
                                 f"this file before an edit, or a damaged {MANIFEST}); choose "
                                 f"another --out folder or delete {self.out}")
        self.folder.mkdir(parents=True, exist_ok=True)
        for stale in self.folder.glob(".chunk-*.partial-*"):    # of a killed writer (the
            stale.unlink(missing_ok=True)                       # lock is ours: none live)
        atomic_write(manifest, json.dumps(
            {"fingerprint": self.fingerprint, "name": sweep.name, "source": sweep.source,
             "flights": len(sweep.flights), "chunks": len(sweep.chunks())}, indent=2) + "\n")

    def path(self, c: int) -> Path:
        """The file of chunk ``c``.

        Parameters
        ----------
        c : int
            The chunk index.

        Returns
        -------
        pathlib.Path
            ``out/chunks/chunk-NNNNN.parquet``.
        """
        return self.folder / f"chunk-{c:05d}.parquet"

    def done(self, c: int) -> bool:
        """Whether chunk ``c`` is stored.

        Parameters
        ----------
        c : int
            The chunk index.

        Returns
        -------
        bool
            True when its file exists (it is complete: files are renamed into place).
        """
        return self.path(c).is_file()

    def write(self, c: int, table: Any, flights: Sequence[int]) -> None:
        """Store chunk ``c`` (to a temporary name, then renamed), with its record.

        Parameters
        ----------
        c : int
            The chunk index.
        table : pyarrow.Table
            One row per flight of the chunk.
        flights : sequence of int
            The flight indices of its rows (part of the record a resume verifies).
        """
        pa = require_pyarrow()
        meta = dict(table.schema.metadata or {})
        meta.update(chunk_metadata(table, self.fingerprint, c, flights))
        tmp = self.path(c).with_name(f".{self.path(c).name}.partial-{os.getpid()}")
        try:
            pa.parquet.write_table(table.replace_schema_metadata(meta), tmp)
            os.replace(tmp, self.path(c))
        finally:
            if tmp.exists():
                tmp.unlink()

    def verified(self, c: int, flights: Sequence[int]
                 ) -> tuple[dict[str, NDArray[Any]] | None, str | None]:
        """The stored result of chunk ``c``, when it verifies for these flights.

        Parameters
        ----------
        c : int
            The chunk index.
        flights : sequence of int
            The flight indices the chunk must hold.

        Returns
        -------
        tuple of (dict or None, str or None)
            ({column: (n,) array}, None) when the file is this sweep's chunk ``c`` with these
            flights, row count and checksum (``quadcog.sweeps.integrity``), else (None, the
            reason).
        """
        table, reason = verify_chunk(self.path(c), self.fingerprint, c, flights)
        return (None, reason) if table is None else (columns_of_table(table), None)


def _concat(parts):
    names = list(parts[0])
    return {k: np.concatenate([p[k] for p in parts]) for k in names}


def _local(jobs, workers, on_done):
    """Chunks on local processes; a single process (this one, with its threads) when there is
    one worker or one chunk."""
    workers = max(1, min(workers, len(jobs)))
    if workers == 1:
        for job in jobs:
            on_done(job["chunk"], run_chunk(job, threads=os.cpu_count() or 1))
        return
    # fork where it is safe (Linux; no threads are running here yet): no `if __name__ ==
    # "__main__"` guard is needed in the caller's script, and the children start at once
    methods = multiprocessing.get_all_start_methods()
    ctx = multiprocessing.get_context("fork" if sys.platform.startswith("linux")
                                      and "fork" in methods else "spawn")
    pool = ProcessPoolExecutor(max_workers=workers, mp_context=ctx,
                               initializer=die_with_parent)
    try:
        futures = {pool.submit(run_chunk, job): job["chunk"] for job in jobs}
        for fut in as_completed(futures):
            on_done(futures[fut], fut.result())
    except BaseException:
        # Ctrl-C, SIGTERM or a failed chunk: end the workers now, not after their chunks
        for proc in list(getattr(pool, "_processes", {}).values()):
            if proc.is_alive():
                proc.kill()
        pool.shutdown(wait=True, cancel_futures=True)
        raise
    pool.shutdown(wait=True)


def _dask(jobs, workers, scheduler, fingerprint, on_done):
    """Chunks on Dask: a LocalCluster of ``workers`` processes, or the cluster at
    ``scheduler``. A task whose worker dies is run again elsewhere (Dask reschedules it)."""
    try:
        from distributed import Client, LocalCluster
        from distributed import as_completed as dask_completed
    except ImportError:
        raise QuadcogError("--workers/--scheduler need Dask: pip install 'quadcog[sweep]'") \
            from None
    import logging
    cluster = None
    try:
        if scheduler:
            try:
                client = Client(scheduler, timeout="20s")
            except (OSError, TimeoutError) as e:
                raise SchedulerError(f"--scheduler {scheduler}: cannot connect ({e})") from None
        else:
            with children_without_sigint():     # Ctrl-C reaches this process only
                cluster = LocalCluster(n_workers=workers, threads_per_worker=1, processes=True,
                                       # a failed task reaches us as its exception;
                                       # the workers' own log lines (a heartbeat that
                                       # finds the scheduler closed on Ctrl-C) are noise
                                       dashboard_address=None, silence_logs=logging.CRITICAL,
                                       preload=["quadcog.sweeps.worker_setup"])
                client = Client(cluster)
        with client:
            futures = {client.submit(run_chunk, job, key=f"quadcog-{fingerprint[:16]}-"
                                     f"{job['chunk']}", retries=3): job["chunk"]
                       for job in jobs}
            for fut in dask_completed(futures):
                on_done(futures[fut], fut.result())
    finally:
        if cluster is not None:
            cluster.close()


class SweepResult:
    """The outcome of a sweep.

    Parameters
    ----------
    sweep : quadcog.sweeps.spec.Sweep
        The sweep itself.
    columns : dict of str to numpy.ndarray
        {name: (n_flights,) array}, one row per flight, in flight order.
    summary : dict
        ``quadcog.sweeps.summary.summarize`` of the columns.
    out : str or os.PathLike or None
        The results folder, or None (kept in memory).
    seconds : float
        Wall time of the call [s].
    flown : int
        Flights simulated by this call: not those of resumed chunks, nor inadmissible ones.
    rejected : sequence of (int, str)
        (chunk index, reason) of the chunk files found in ``out`` that did not verify and
        were flown again.
    """

    def __init__(self, sweep: Sweep, columns: dict[str, NDArray[Any]], summary: dict[str, Any],
                 out: str | os.PathLike[str] | None, seconds: float, flown: int,
                 rejected: Sequence[tuple[int, str]] = ()) -> None:
        self.sweep, self.columns, self.summary = sweep, columns, summary
        self.out, self.seconds, self.flown = out, seconds, flown
        self.rejected = list(rejected)

    def table(self) -> Any:
        """The results as a pyarrow Table.

        Returns
        -------
        pyarrow.Table
            One row per flight (pyarrow ships no type stubs: typed as Any).
        """
        return to_arrow(self.columns)

    def to_arrow(self) -> Any:
        """The results as a pyarrow Table (needs the sweep extra).

        Returns
        -------
        pyarrow.Table
            One row per flight, the columns of ``columns``.
        """
        return to_arrow(self.columns)

    def to_pandas(self) -> Any:
        """The results as a pandas DataFrame (needs pandas).

        Returns
        -------
        pandas.DataFrame
            One row per flight, the columns of ``columns``.
        """
        return self.to_arrow().to_pandas()


def sweep(spec: str | os.PathLike[str] | dict[str, Any] | Sweep,
          out: str | os.PathLike[str] | None = None, *, workers: int | None = None,
          scheduler: str | None = None, progress: bool | Callable[[int], object] = True,
          plots: bool = True, **settings: Any) -> SweepResult:
    """Run a sweep file and collect one row per flight.

    Parameters
    ----------
    spec : str, os.PathLike, dict or Sweep
        A sweep file, the name of a shipped sweep (``"failure-map"``), a parsed sweep file
        (dict), or a Sweep from ``load_sweep``.
    out : str or os.PathLike, optional
        Folder for ``results.parquet``, ``results.csv``, ``summary.json``, ``summary.md``,
        the plots, and the per-chunk results that make a killed run resumable (run the same
        sweep with the same folder again). None: keep everything in memory.
    workers : int, optional
        Start a Dask LocalCluster of this many worker processes.
    scheduler : str, optional
        Address of a running Dask scheduler (``tcp://host:8786``) to use instead.
    progress : bool or callable
        True: flights done of total, with the rate, on stderr; a callable(n_new) is called
        as chunks finish; False: quiet.
    plots : bool
        Draw the plots into ``out`` (needs matplotlib).
    **settings
        Top-level keys of the sweep file to replace (``seed=2``, ``chunk=16``).

    Returns
    -------
    SweepResult
        One row per flight, the summary, the timing.

    Raises
    ------
    quadcog.errors.SweepError
        For an invalid sweep file or settings, both ``workers`` and ``scheduler``, or an
        ``out`` folder holding another sweep's results.
    quadcog.errors.QuadcogError
        When Dask or pyarrow is needed and missing, or the scheduler cannot be reached.
    """
    t0 = time.perf_counter()
    # the extras are checked before any work (reading the file, expanding the flights)
    if out is not None:
        validate.require_extra("sweep", "pyarrow")
    if workers is not None or scheduler is not None:
        validate.require_extra("sweep", "dask", "distributed")
    check_backend(workers, scheduler, out)
    if isinstance(spec, Sweep):
        s = spec
    elif isinstance(spec, dict):
        source = settings.pop("source", "<sweep>")
        s = from_dict(dict(spec, **settings), source, progress=progress is True)
    else:
        s = load_sweep(spec, progress=progress is True, **settings)
    def say(text: str) -> None:
        if progress:            # the name from the file: one line, shortened
            print(one_line(f"sweep {s.name}: {text}", word=120), file=sys.stderr)
    if scheduler is not None:           # before any folder is made: it answers, or an error
        scheduler = probe_scheduler(scheduler)
    if out is None:
        return _run(s, None, workers, scheduler, progress, plots, say, t0)
    out = Path(out)
    check_outputs([(f"--out (its {name})", out / name) for name in output_names(s)], s.inputs,
                  SweepError, folders=[(f"--out (its {CHUNK_FOLDER}/)", out / CHUNK_FOLDER)])
    try:
        out.mkdir(parents=True, exist_ok=True)
    except OSError as e:
        raise QuadcogError(f"out = {str(out)!r}: cannot create the folder ({e.strerror})") \
            from None
    with SweepLock(out, say):
        return _run(s, out, workers, scheduler, progress, plots, say, t0)


def output_names(s: Sweep) -> list[str]:
    """The files a sweep writes into its results folder (besides ``chunks/``).

    Parameters
    ----------
    s : quadcog.sweeps.spec.Sweep
        The sweep.

    Returns
    -------
    list of str
        File names: the manifest, the lock, the tables, the summaries and every plot the
        dimensions may give (``quadcog.sweeps.summary.plot_sweep``).
    """
    import re
    plots = ["failure_map.png", "tail_rms_hist.png"] + [
        "survival_" + re.sub(r"[^A-Za-z0-9]+", "_", c).strip("_") + ".png" for c in s.columns]
    return [MANIFEST, LOCK_NAME, "results.parquet", "results.csv", "summary.json",
            "summary.md", *plots]


def check_backend(workers: object, scheduler: object, out: object = None) -> None:
    """Refuse a wrong ``workers``, ``scheduler`` or ``out`` before any work.

    Parameters
    ----------
    workers : int or None
        Whole number 1..MAX_WORKERS (not a bool).
    scheduler : str or None
        A Dask scheduler address (``quadcog.sweeps.scheduler.parse_address``).
    out : str, os.PathLike or None
        The results folder.

    Returns
    -------
    None
    """
    import numbers

    from quadcog.sweeps.scheduler import parse_address
    if workers is not None and scheduler is not None:
        raise SweepError("give --workers or --scheduler, not both")
    if workers is not None:
        if isinstance(workers, bool) or not isinstance(workers, numbers.Integral) \
                or int(workers) < 1:
            raise SweepError(f"workers: expected a whole number >= 1, got {workers!r}")
        if int(workers) > MAX_WORKERS:
            raise SizeError(f"workers = {workers}: more than {MAX_WORKERS} worker processes "
                            f"is refused (each is a Python process with its own compiled "
                            f"code); use a Dask cluster (--scheduler) for more")
    if scheduler is not None:
        parse_address(scheduler, "scheduler")
    if out is not None and not isinstance(out, (str, os.PathLike)):
        raise SweepError(f"out: expected a folder path (str or os.PathLike) or None, got "
                         f"{out!r} ({type(out).__name__})")


def _run(s, out, workers, scheduler, progress, plots, say, t0):
    """Fly (or resume) sweep ``s`` into ``out`` (None: in memory); the lock is held."""
    chunks = s.chunks()
    store = ChunkStore(out, s) if out is not None else None
    results: dict[int, dict[str, NDArray[Any]] | None] = {}
    pending = []
    rejected = []
    for c, flights in chunks:
        indices = [f.index for f in flights]
        if store is not None and store.done(c):
            columns, reason = store.verified(c, indices)
            if columns is not None:
                results[c] = columns
                continue
            rejected.append((c, reason))
            say(f"{store.path(c).name} does not verify ({reason}): flying it again")
        pending.append(make_job(s, c, flights))
    done_flights = len(s.flights) - sum(len(j["flights"]) for j in pending)
    if callable(progress):
        report = progress
    elif progress:
        report = ProgressCounter(f"sweep {s.name}", len(s.flights), done_flights)
        if done_flights:
            print(one_line(f"sweep {s.name}: resuming, {len(chunks) - len(pending)} of "
                           f"{len(chunks)} chunks already in {out} (verified)", word=120),
                  file=sys.stderr)
    else:
        report = None

    def on_done(c, columns):
        # through Arrow and back, as a resumed chunk is read: the same arrays either way
        table = to_arrow(columns)
        if store is not None:
            store.write(c, table, [f.index for f in chunks[c][1]])
        results[c] = columns_of_table(table)
        if report:
            report(len(columns["flight"]))

    if pending:
        if scheduler is not None or workers is not None:
            _dask(pending, workers, scheduler, store.fingerprint if store else s.fingerprint(),
                  on_done)
        else:
            _local(pending, os.cpu_count() or 1, on_done)
    columns = _concat([results[c] for c, _ in chunks])
    from quadcog.sweeps.summary import summarize, write_outputs
    summary = summarize(s, columns)
    if out is not None:
        write_outputs(s, columns, summary, Path(out), plots=plots)
    flown = sum(f[2] for j in pending for f in j["flights"])     # admissible ones only
    return SweepResult(s, columns, summary, out, time.perf_counter() - t0, flown, rejected)


def run_cli(spec: str | os.PathLike[str], out: str | os.PathLike[str],
            workers: int | None = None, scheduler: str | None = None) -> SweepResult:
    """`quadcog sweep FILE --out DIR`: run (or resume), then print the summary table.

    Parameters
    ----------
    spec : str or os.PathLike
        A sweep file, or the name of a shipped sweep.
    out : str or os.PathLike
        The results folder.
    workers : int, optional
        Processes of a Dask LocalCluster.
    scheduler : str, optional
        Address of a running Dask scheduler.

    Returns
    -------
    SweepResult
        The outcome.
    """
    from quadcog.sweeps.summary import summary_markdown
    result = sweep(spec, out, workers=workers, scheduler=scheduler)
    print(summary_markdown(result.summary))
    print(f"{result.flown} flights flown in {result.seconds:.1f} s; wrote {out}/results.parquet, "
          f"results.csv, summary.md, summary.json and plots")
    return result
