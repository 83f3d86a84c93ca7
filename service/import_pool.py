"""Profile processing of an import's chunks: in a pool of worker processes, or in this one.

A chunk's profiles are cleaned, placed, aligned to their declared reference and turned into
wear curves, areas and Sd/Sh/qR (:mod:`wearcast.service.import_worker`, which the spawned
workers import alone; free-fit profiles are processed together, a block of rows at a
time). Chunks of at least :data:`PARALLEL_MIN_PROFILES` new profiles go to a pool of one
worker per core (``WEARCAST_IMPORT_WORKERS`` overrides; 0 or 1: none), so the
caller can parse and insert meanwhile; smaller ones, and any chunk when the pool cannot run,
are processed in the calling process with the same results.
"""

from __future__ import annotations

import multiprocessing
import os
import threading
from collections.abc import Callable
from concurrent.futures import ProcessPoolExecutor
from concurrent.futures.process import BrokenProcessPool

import numpy as np

from wearcast.service.import_registry import ImportRegistry
from wearcast.service.import_worker import Processed, RefTuple, process_arrays, process_batch
from wearcast.service.readers.errors import ImportFileError
from wearcast.service.readers.records import ProfileRecord
from wearcast.service.reference_store import ReferenceSpec

#: Chunks with at least this many new profiles are processed by a pool of worker processes;
#: smaller ones (single posts, the example fleet, tests) stay in the calling process.
PARALLEL_MIN_PROFILES = 256


def ref_tuple(spec: ReferenceSpec | None) -> RefTuple | None:
    """A resolved reference as the plain tuple the processing (and its workers) take."""
    return None if spec is None else (spec.name, spec.kind, spec.y_mm, spec.z_mm)


def process_with_reference(y_mm: np.ndarray, z_mm: np.ndarray,
                           spec: ReferenceSpec | None = None,
                           datum: bool = False) -> Processed | str:
    """The processed profile, or the reason it cannot be used (see
    :func:`wearcast.service.import_worker.process_arrays`); ``spec`` is the declared
    reference (default S1002)."""
    return process_arrays(y_mm, z_mm, ref_tuple(spec), datum)


_POOL: ProcessPoolExecutor | None = None
_POOL_WORKERS = 0
_POOL_LOCK = threading.Lock()


def configured_workers() -> int:
    """Worker processes of the pool: ``WEARCAST_IMPORT_WORKERS``, else one per core (0 or 1:
    no pool)."""
    configured = os.environ.get("WEARCAST_IMPORT_WORKERS", "").strip()  # empty: unset
    return int(configured) if configured else (os.cpu_count() or 1)


def worker_pool() -> ProcessPoolExecutor | None:
    """A process pool of one worker per core (spawned once, on the first large chunk).

    ``spawn`` rather than ``fork``: the service runs threads, and forking a threaded process
    can inherit held locks. None on a single core or when ``WEARCAST_IMPORT_WORKERS=0``.
    """
    global _POOL, _POOL_WORKERS
    workers = configured_workers()
    if workers <= 1:
        return None
    with _POOL_LOCK:
        if _POOL is None:
            _POOL = ProcessPoolExecutor(workers, mp_context=multiprocessing.get_context("spawn"))
            _POOL_WORKERS = workers
        return _POOL


def pool_workers() -> int:
    """The number of worker processes of the running pool (0 when none runs)."""
    return _POOL_WORKERS if _POOL is not None else 0


def discard_pool(wait: bool = False) -> None:
    """Shut the worker pool down (a broken pool, or the service stopping); with ``wait``,
    until its processes have exited (e.g. for a benchmark to read their resource use)."""
    global _POOL
    with _POOL_LOCK:
        if _POOL is not None:
            _POOL.shutdown(wait=wait, cancel_futures=True)
        _POOL = None


def submit_profiles(records: list[ProfileRecord], registry: ImportRegistry | None = None
                    ) -> Callable[[], list[Processed]]:
    """Start processing a chunk's profiles; the returned callable waits for the results.

    Large chunks go to the worker pool, so the caller can parse and insert meanwhile; a pool
    that cannot run (e.g. a script without a ``__main__`` guard under ``spawn``) falls back to
    processing in this process. The callable raises the ImportFileError of the first unusable
    profile, naming its file and line.
    """
    specs = [registry.reference(r) if registry is not None else None for r in records]
    arrays = [(r.y_mm, r.z_mm, ref_tuple(spec), r.instrument_datum)
              for r, spec in zip(records, specs, strict=True)]
    pool = worker_pool() if len(records) >= PARALLEL_MIN_PROFILES else None
    futures = []
    if pool is not None:
        size = -(-len(arrays) // (_POOL_WORKERS * 2))
        try:
            futures = [pool.submit(process_batch, arrays[i:i + size])
                       for i in range(0, len(arrays), size)]
        except (BrokenProcessPool, RuntimeError):
            discard_pool()
            futures = []

    def results() -> list[Processed]:
        try:
            done = [r for f in futures for r in f.result()] if futures else None
        except BrokenProcessPool:
            discard_pool()
            done = None
        if done is None:
            done = process_batch(arrays)
        for record, result in zip(records, done, strict=True):
            if isinstance(result, str):
                meta = record.meta
                raise ImportFileError(meta.source_file, f"profile of wheel {meta.wheel_id!r} "
                                      f"at {meta.mileage_km:g} km cannot be used: {result}",
                                      line=meta.source_line, field="z_mm")
        return done  # type: ignore[return-value]

    return results
