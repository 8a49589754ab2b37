"""Where units of work run: in this process, in local worker processes, or on a Dask cluster.

All three offer ``submit`` (returns a future with ``result()``) and ``wait_any`` (block until
at least one of the given futures is done), which is all :mod:`sweeps.run` needs.

Local workers are forked (``multiprocessing`` "fork" context) rather than spawned: a spawned
child re-imports the parent's ``__main__``, and ``python -m lyapcheck`` runs the command line
at import. The pool is started, and every worker forked, before the progress bar's thread
exists (:meth:`ProcessRunner.start`), so no thread is ever duplicated into a worker. Each
worker reads the compiled certificate programs once, on its first unit, and re-solves them
afterwards (:mod:`lyapcheck.paper.conditions.compiled`).
"""

from __future__ import annotations

import concurrent.futures as cf
import multiprocessing
import os
from typing import Any, Callable, Iterable, Protocol


class Runner(Protocol):
    """What the sweep needs from an executor."""

    workers: int

    def start(self) -> None: ...

    def submit(self, fn: Callable[..., Any], *args: Any) -> Any: ...

    def wait_any(self, futures: Iterable[Any]) -> tuple[set[Any], set[Any]]: ...

    def close(self, *, cancel: bool = False) -> None: ...


def _noop() -> int:
    return os.getpid()


class InlineRunner:
    """Runs each unit at submission, in this process (tests, benchmarks, debugging)."""

    workers = 1

    def start(self) -> None:
        return None

    def submit(self, fn: Callable[..., Any], *args: Any) -> cf.Future[Any]:
        future: cf.Future[Any] = cf.Future()
        try:
            future.set_result(fn(*args))
        except BaseException as exc:  # handed over like a pool would; re-raised by result()
            if isinstance(exc, KeyboardInterrupt):
                raise
            future.set_exception(exc)
        return future

    def wait_any(self, futures: Iterable[Any]) -> tuple[set[Any], set[Any]]:
        done, pending = cf.wait(list(futures), return_when=cf.FIRST_COMPLETED)
        return set(done), set(pending)

    def close(self, *, cancel: bool = False) -> None:
        return None


class ProcessRunner:
    """Local worker processes (default: one per core)."""

    def __init__(self, workers: int | None = None) -> None:
        self.workers = workers if workers is not None else (os.cpu_count() or 1)
        self._pool: cf.ProcessPoolExecutor | None = None

    def start(self) -> None:
        context = multiprocessing.get_context("fork")
        self._pool = cf.ProcessPoolExecutor(max_workers=self.workers, mp_context=context)
        # the first submission forks every worker (fork context): do it now, before any thread
        self._pool.submit(_noop).result()

    def submit(self, fn: Callable[..., Any], *args: Any) -> cf.Future[Any]:
        if self._pool is None:
            self.start()
        assert self._pool is not None
        return self._pool.submit(fn, *args)

    def wait_any(self, futures: Iterable[Any]) -> tuple[set[Any], set[Any]]:
        done, pending = cf.wait(list(futures), return_when=cf.FIRST_COMPLETED)
        return set(done), set(pending)

    def close(self, *, cancel: bool = False) -> None:
        if self._pool is not None:
            self._pool.shutdown(wait=not cancel, cancel_futures=cancel)
            self._pool = None


class DaskRunner:
    """An existing Dask distributed cluster, reached through its scheduler address."""

    def __init__(self, address: str) -> None:
        self.address = address
        self._client: Any = None
        self.workers = 1

    def start(self) -> None:
        from distributed import Client

        from lyapcheck.errors import InputFileError

        try:
            self._client = Client(self.address, timeout="10s")
        except (OSError, TimeoutError, ValueError) as exc:
            raise InputFileError(f"cannot reach the Dask scheduler at '{self.address}': {exc}") from None
        info = self._client.scheduler_info()
        self.workers = max(1, sum(w.get("nthreads", 1) for w in info.get("workers", {}).values()))

    def submit(self, fn: Callable[..., Any], *args: Any) -> Any:
        if self._client is None:
            self.start()
        # pure=False: two units never share a key, and a resubmission after a failure reruns
        return self._client.submit(fn, *args, pure=False)

    def wait_any(self, futures: Iterable[Any]) -> tuple[set[Any], set[Any]]:
        from distributed import wait

        result = wait(list(futures), return_when="FIRST_COMPLETED")
        return set(result.done), set(result.not_done)

    def close(self, *, cancel: bool = False) -> None:
        if self._client is not None:
            self._client.close()
            self._client = None


def make_runner(*, scheduler: str | None = None, workers: int | None = None) -> Runner:
    """``scheduler`` (a Dask address) wins; ``workers == 0`` runs in this process."""
    if scheduler:
        return DaskRunner(scheduler)
    if workers == 0:
        return InlineRunner()
    return ProcessRunner(workers)
