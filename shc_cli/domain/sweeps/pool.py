"""Where runs execute: this process, a pool of worker processes, or a Dask cluster."""

from __future__ import annotations

from collections.abc import Iterator
from pathlib import Path
from types import TracebackType
from typing import Any

from shc_cli.domain.sweeps import points
from shc_cli.domain.sweeps.results import METRICS, Row
from shc_cli.errors import Interrupted, Issue, SpecError, install_hint, signal_name
from shc_cli.spec.sweep import Point


def _terminated(error: BaseException | None) -> bool:
    """``error`` is a SIGTERM's (:class:`~shc_cli.errors.Terminated`, or the Interrupted that says what was kept)."""
    return isinstance(error, (KeyboardInterrupt, Interrupted)) and signal_name(error) == "SIGTERM"


class RunPool:
    """Where runs execute: in this process (one worker), a pool of worker processes, or a Dask cluster — kept
    open across batches (``shc optimize`` submits one batch of trials at a time). Use as a context manager.

    Dask: the scheduler at ``scheduler``, or a LocalCluster of ``workers`` single-threaded worker processes;
    workers need shc installed and must see the output directory (a shared file system).

    Every run is :func:`shc_cli.domain.sweeps.points.run_point` (looked up at each call, so tests can stub it).
    """

    def __init__(self, executor: str, workers: int, scheduler: str | None) -> None:
        self.executor, self.workers, self.scheduler = executor, workers, scheduler
        self._pool: Any = None  # concurrent.futures.ProcessPoolExecutor
        self._client: Any = None  # dask.distributed, an untyped library
        self._cluster: Any = None
        self._out: Path | None = None  # the output directory of the runs (their stop request goes there)
        self._dask: Any = None

    def __enter__(self) -> RunPool:
        if self.executor == "dask":
            try:
                from dask import distributed
            except ImportError:
                raise SpecError([Issue(None, None, "--executor", "dask is not installed",
                                       f"{install_hint('dask')}, or use --executor local")]) from None
            self._dask = distributed
            if self.scheduler is None:
                self._cluster = self._dask.LocalCluster(n_workers=self.workers, threads_per_worker=1, processes=True,
                                                        dashboard_address=None)
            self._client = self._dask.Client(self._cluster if self._cluster is not None else self.scheduler)
        elif self.workers > 1:
            from concurrent.futures import ProcessPoolExecutor

            self._pool = ProcessPoolExecutor(max_workers=self.workers)
        return self

    def __exit__(self, kind: type[BaseException] | None, error: BaseException | None,
                 trace: TracebackType | None) -> None:
        if self._pool is not None:
            interrupted = kind is not None
            if self._out is not None and isinstance(error, (KeyboardInterrupt, Interrupted)):
                points.request_stop(self._out, signal_name(error))  # the runs still queued in the workers end at once
            if _terminated(error):  # a SIGTERM reached only this process (a Ctrl-C reaches the workers too)
                for process in list((getattr(self._pool, "_processes", None) or {}).values()):
                    process.terminate()  # each finishes its run as a partial one, as at a Ctrl-C, and stops
            self._pool.shutdown(wait=not interrupted, cancel_futures=interrupted)
        if self._client is not None:
            self._client.close()
        if self._cluster is not None:
            self._cluster.close()

    def results(self, batch: list[Point], out: Path, metrics: tuple[str, ...] = METRICS,
                skip: float = 0.0) -> Iterator[Row]:
        """Rows of :func:`~shc_cli.domain.sweeps.points.run_point` as the runs finish (in order with one local
        worker)."""
        run_point = points.run_point
        self._out = out
        if self._client is not None:
            futures = self._client.map(run_point, batch, out=str(out.resolve()), metrics=metrics, skip=skip,
                                       pure=False)
            for future in self._dask.as_completed(futures):
                yield future.result()
            return
        if self._pool is None:
            for point in batch:
                yield run_point(point, str(out), metrics, skip)
            return
        from concurrent.futures import as_completed

        futures = {self._pool.submit(run_point, point, str(out), metrics, skip): point for point in batch}
        for future in as_completed(futures):
            point = futures[future]
            error = future.exception()
            if error is not None:  # the worker process itself died
                yield points.failed_row(point, error)
            else:
                yield future.result()
