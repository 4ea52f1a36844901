"""Where the batches run: the Dask client (a running scheduler's, or a local cluster started and
closed here), the variants cut into batches and sized by timing one, and the progress on stderr."""

import math
import os
import re
import sys
import time

from ._sweep_errors import _error, _excerpt
from ._sweep_metrics import run_batch
from ._sweep_spec import MAX_BATCH


# A batch should take about this long on a worker: hundreds of times a task's overhead (a few ms
# through a local scheduler and back, README.md's scaling table), so scheduling costs well under
# 1%; a 10^6-variant sweep stays at tens of thousands of tasks and batch files; a kill loses at
# most this much work per worker, and the progress bar still moves.
TARGET_BATCH_SECONDS = 2.0
# ...and each worker should get at least this many batches, so that a slow batch does not leave
# the others idle at the end.
MIN_BATCHES_PER_WORKER = 4


class _Progress:
    """count done, rate and time left on stderr: in place on a terminal, else a line at most every
    10 s (a log file is not flooded)."""

    def __init__(self, total, done, unit, enabled):
        self.total, self.done, self.unit, self.enabled = total, done, unit, enabled
        self.start_done, self.started, self.last = done, time.monotonic(), 0.0
        self.tty = enabled and sys.stderr.isatty()

    def restart(self):
        self.start_done, self.started = self.done, time.monotonic()

    def add(self, n, final=False):
        self.done += n
        now = time.monotonic()
        if not self.enabled or (not final and now - self.last < (0.2 if self.tty else 10.0)):
            return
        self.last = now
        elapsed = max(now - self.started, 1e-9)
        rate = (self.done - self.start_done) / elapsed
        left = (self.total - self.done) / rate if rate > 0 else float("inf")
        width = 30
        filled = int(width * self.done / max(self.total, 1))
        bar = "#" * filled + "-" * (width - filled)
        eta = "--" if not math.isfinite(left) else (f"{left:.0f} s" if left < 120 else f"{left / 60:.1f} min")
        line = f"sweep [{bar}] {self.done}/{self.total} {self.unit} {rate:.1f}/s, {eta} left"
        try:
            sys.stderr.write(("\r" + line + ("\n" if final else "")) if self.tty else line + "\n")
            sys.stderr.flush()
        except OSError:  # a closed stderr never stops a sweep
            pass


def _batch_size(plan, reference, pending, workers, given):
    """Variants per task: `given`, else sized so that a batch takes about TARGET_BATCH_SECONDS on
    a worker (timed on one variant here) and each worker gets at least MIN_BATCHES_PER_WORKER."""
    if given is not None:
        return given
    if not pending:
        return 1
    index = pending[0]
    started = time.perf_counter()
    run_batch(reference, plan.names, plan.runs, plan.metrics, [index], plan.values[index:index + 1].tolist())
    per_variant = max(time.perf_counter() - started, 1e-6)
    by_time = max(1, int(TARGET_BATCH_SECONDS / per_variant))
    by_balance = max(1, math.ceil(len(pending) / (MIN_BATCHES_PER_WORKER * max(workers, 1))))
    return max(1, min(by_time, by_balance, MAX_BATCH))


def _client_for(client, scheduler, workers):
    """(client, cluster we started or None). A local cluster: one single-threaded worker process per
    core (the runs hold the GIL, so threads would not run in parallel)."""
    if client is not None:
        return client, None
    import logging

    from distributed import Client, LocalCluster

    if scheduler is not None:
        if not isinstance(scheduler, str) or not re.fullmatch(r"(tcp|tls|ucx)://[^\s/]+(:\d+)?", scheduler):
            _error("scheduler", f"expected an address such as tcp://HOST:8786, got {_excerpt(scheduler)}")
        try:
            return Client(scheduler, timeout="10s"), None
        except (OSError, TimeoutError) as e:
            _error("scheduler", f"cannot reach {scheduler}: {e}")
    # Every server of a local cluster (the scheduler, its HTTP routes, each worker and its nanny)
    # listens on the loopback address only: dashboard_address=None alone leaves the scheduler's
    # HTTP server (/info, /json, /metrics) on 0.0.0.0:8787.
    cluster = LocalCluster(n_workers=workers, threads_per_worker=1, processes=True, host="127.0.0.1",
                           dashboard_address="127.0.0.1:0", worker_dashboard_address="127.0.0.1:0",
                           silence_logs=logging.ERROR)
    return Client(cluster), cluster


def _default_workers():
    try:
        return len(os.sched_getaffinity(0))
    except AttributeError:  # pragma: no cover - not Linux
        return os.cpu_count() or 1


def _batches(pending, size):
    """Runs of consecutive pending variants, cut into batches of at most `size`: a batch never
    spans a variant already written, so every batch file covers one range and results.csv is the
    files concatenated in order."""
    out, start = [], 0
    for k in range(1, len(pending) + 1):
        if k == len(pending) or pending[k] != pending[k - 1] + 1:
            run = pending[start:k]
            out += [run[j:j + size] for j in range(0, len(run), size)]
            start = k
    return out
