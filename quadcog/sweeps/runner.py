"""Run a sweep: chunks of flights on local processes (default), a Dask LocalCluster
(``workers``) or an existing Dask cluster (``scheduler``); results stored per chunk, so a killed
run resumes where it stopped.

The result of a chunk depends on the chunk alone (fixed flights, seeded values, independent
lanes), never on where or when it ran: every backend and every resumed run gives the same
bits.
"""
from concurrent.futures import ProcessPoolExecutor, as_completed
import json
import multiprocessing
import os
from pathlib import Path
import sys
import time

import numpy as np

from quadcog import validate
from quadcog.errors import QuadcogError
from quadcog.files import atomic_write
from quadcog.sweeps.flights import make_job, run_chunk
from quadcog.sweeps.spec import Sweep, SweepError, from_dict, load_sweep
from quadcog.sweeps.table import require_pyarrow, to_arrow

CHUNK_FOLDER = "chunks"
MANIFEST = "sweep.json"


class Progress:
    """``done/total flights (percent), rate, time left`` on stderr: live on a terminal, every
    few seconds (and at the end) in a log."""

    def __init__(self, label, total, done=0, stream=None, every=5.0):
        self.label, self.total, self.done = label, total, done
        self.stream = stream or sys.stderr
        self._start_done, self._t0 = done, time.perf_counter()
        self._last, self._every = -1e9, every
        self._live = getattr(self.stream, "isatty", lambda: False)()

    def __call__(self, n_new):
        self.done += n_new
        now = time.perf_counter()
        if self.done < self.total and now - self._last < (0.2 if self._live else self._every):
            return
        self._last = now
        rate = (self.done - self._start_done) / max(now - self._t0, 1e-9)
        left = (self.total - self.done) / rate if rate > 0 else float("inf")
        text = (f"{self.label}: {self.done}/{self.total} flights "
                f"({100 * self.done / max(self.total, 1):.0f} %), {rate:.1f} flights/s"
                + (f", {left:.0f} s left" if self.done < self.total and np.isfinite(left) else ""))
        self.stream.write(("\r" + text + " " * 8) if self._live else text + "\n")
        if self._live and self.done >= self.total:
            self.stream.write("\n")
        self.stream.flush()


class ChunkStore:
    """``out/sweep.json`` (the sweep's fingerprint) and ``out/chunks/chunk-NNNNN.parquet``,
    each written to a temporary name and renamed, so a chunk file is complete or absent."""

    def __init__(self, out, sweep):
        self.out = Path(out)
        self.folder = self.out / CHUNK_FOLDER
        self.fingerprint = sweep.fingerprint()
        manifest = self.out / MANIFEST
        if manifest.is_file():
            try:
                old = json.loads(manifest.read_text()).get("fingerprint")
            except (ValueError, OSError):
                old = None
            if old != self.fingerprint:
                raise SweepError(f"{self.out}: holds the results of a different sweep (or of "
                                 f"this file before an edit); choose another --out folder or "
                                 f"delete {self.out}")
        self.folder.mkdir(parents=True, exist_ok=True)
        atomic_write(manifest, json.dumps(
            {"fingerprint": self.fingerprint, "name": sweep.name, "source": sweep.source,
             "flights": len(sweep.flights), "chunks": len(sweep.chunks())}, indent=2) + "\n")

    def path(self, c):
        return self.folder / f"chunk-{c:05d}.parquet"

    def done(self, c):
        return self.path(c).is_file()

    def write(self, c, columns):
        pa = require_pyarrow()
        tmp = self.path(c).with_suffix(".tmp")
        pa.parquet.write_table(to_arrow(columns), tmp)
        os.replace(tmp, self.path(c))

    def read(self, c):
        pa = require_pyarrow()
        table = pa.parquet.read_table(self.path(c))
        return {name: table.column(name).to_numpy(zero_copy_only=False)
                for name in table.column_names}


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
    with ProcessPoolExecutor(max_workers=workers, mp_context=ctx) as pool:
        futures = {pool.submit(run_chunk, job): job["chunk"] for job in jobs}
        for fut in as_completed(futures):
            on_done(futures[fut], fut.result())


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
                raise QuadcogError(f"--scheduler {scheduler}: cannot connect ({e})") from None
        else:
            cluster = LocalCluster(n_workers=workers, threads_per_worker=1, processes=True,
                                   dashboard_address=None, silence_logs=logging.ERROR)
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
    """The outcome of a sweep: ``columns`` ({name: array}, one row per flight, in flight
    order), ``summary`` (dict), the ``sweep`` itself, ``out`` (folder or None), ``seconds``
    and ``flown`` (flights simulated by this call: not those of resumed chunks, nor
    inadmissible ones)."""

    def __init__(self, sweep, columns, summary, out, seconds, flown):
        self.sweep, self.columns, self.summary = sweep, columns, summary
        self.out, self.seconds, self.flown = out, seconds, flown

    def table(self):
        """The results as a pyarrow Table."""
        return to_arrow(self.columns)

    def to_arrow(self):
        """The results as a pyarrow Table (one row per flight; needs the sweep extra)."""
        return to_arrow(self.columns)

    def to_pandas(self):
        """The results as a pandas DataFrame (one row per flight; needs pandas)."""
        return self.to_arrow().to_pandas()


def sweep(spec, out=None, *, workers=None, scheduler=None, progress=True, plots=True,
          **settings):
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
    """
    t0 = time.perf_counter()
    # the extras are checked before any work (reading the file, expanding the flights)
    if out is not None:
        validate.require_extra("sweep", "pyarrow")
    if workers is not None or scheduler is not None:
        validate.require_extra("sweep", "dask", "distributed")
    if isinstance(spec, Sweep):
        s = spec
    elif isinstance(spec, dict):
        source = settings.pop("source", "<sweep>")
        s = from_dict(dict(spec, **settings), source)
    else:
        s = load_sweep(spec, **settings)
    if workers is not None and scheduler is not None:
        raise SweepError("give --workers or --scheduler, not both")
    if workers is not None and (not isinstance(workers, int) or workers < 1):
        raise SweepError(f"workers must be a whole number >= 1, got {workers!r}")
    chunks = s.chunks()
    store = ChunkStore(out, s) if out is not None else None
    results = {}
    pending = []
    for c, flights in chunks:
        if store is not None and store.done(c):
            results[c] = None                      # read at the end
        else:
            pending.append(make_job(s, c, flights))
    done_flights = len(s.flights) - sum(len(j["flights"]) for j in pending)
    if callable(progress):
        report = progress
    elif progress:
        report = Progress(f"sweep {s.name}", len(s.flights), done_flights)
        if done_flights:
            print(f"sweep {s.name}: resuming, {len(chunks) - len(pending)} of {len(chunks)} "
                  f"chunks already in {out}", file=sys.stderr)
    else:
        report = None

    def on_done(c, columns):
        if store is not None:
            store.write(c, columns)
        results[c] = columns if store is None else None
        if report:
            report(len(columns["flight"]))

    if pending:
        if scheduler is not None or workers is not None:
            _dask(pending, workers, scheduler, store.fingerprint if store else s.fingerprint(),
                  on_done)
        else:
            _local(pending, os.cpu_count() or 1, on_done)
    columns = _concat([results[c] if store is None else store.read(c) for c, _ in chunks])
    from quadcog.sweeps.summary import summarize, write_outputs
    summary = summarize(s, columns)
    if out is not None:
        write_outputs(s, columns, summary, Path(out), plots=plots)
    flown = sum(f[2] for j in pending for f in j["flights"])     # admissible ones only
    return SweepResult(s, columns, summary, out, time.perf_counter() - t0, flown)


def run_cli(spec, out, workers=None, scheduler=None):
    """`quadcog sweep FILE --out DIR`: run (or resume), then print the summary table."""
    from quadcog.sweeps.summary import summary_markdown
    result = sweep(spec, out, workers=workers, scheduler=scheduler)
    print(summary_markdown(result.summary))
    print(f"{result.flown} flights flown in {result.seconds:.1f} s; wrote {out}/results.parquet, "
          f"results.csv, summary.md, summary.json and plots")
    return result
