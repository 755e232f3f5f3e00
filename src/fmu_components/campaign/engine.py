"""The engine a campaign's tasks run on: Dask distributed.

``Engine(scheduler)`` connects to an existing cluster (``dask scheduler`` on one machine,
``dask worker ADDRESS`` on others); ``Engine(jobs=N)`` starts a local cluster of N worker
processes (default: one per core, never more than there are tasks) and ends it afterwards;
``Engine(jobs=1)``, or a single task without a scheduler, runs in this process, one task
after another (the serial run, no cluster). The cluster starts when the first tasks come. Every way gives the same
numbers: a task is a plain function of its arguments (``payload`` carries the files).

Before any task runs, every worker's installed ``fmu-components`` must be the client's
version: a worker with another one is refused, naming both. A scheduler that cannot be
reached is named within ``CONNECT_TIMEOUT`` seconds. A task that raises comes back as a
``Failure`` with its message; the other tasks go on. A worker lost mid-task costs nothing
but time: the scheduler runs its tasks again on another worker.
"""

import logging
import math
import os
import signal
import sys
import threading
import time
from contextlib import contextmanager
from dataclasses import dataclass
from importlib.metadata import PackageNotFoundError, version

from .payload import resolve

DISTRIBUTION = "fmu-components"
# s: with the command's own start, within the 10 s an engineer waits to hear of a wrong address
CONNECT_TIMEOUT = 5
WORKER_TIMEOUT = 30  # s a reached scheduler gets to show its first worker


# A Dask worker runs numpy's BLAS on one thread (its nanny sets these before it starts), and
# a fit's least squares differs in its last bits with the thread count: the command line
# sets the same in its own process before numpy loads (``one_thread_per_process``), so
# that a serial run gives the workers' numbers bit for bit. A user's own setting stands.
ONE_THREAD = {"OMP_NUM_THREADS": "1", "MKL_NUM_THREADS": "1", "OPENBLAS_NUM_THREADS": "1"}


def one_thread_per_process():
    for name, value in ONE_THREAD.items():
        os.environ.setdefault(name, value)


class EngineError(Exception):
    """A cluster that cannot be used as asked: said in one line, with what to do."""


@dataclass(frozen=True)
class Failure:
    """A task that raised: the exception's type and message."""
    message: str


def package_version():
    try:
        return version(DISTRIBUTION)
    except PackageNotFoundError:
        return None


def cores():
    """The cores this process may run on."""
    try:
        return len(os.sched_getaffinity(0))
    except AttributeError:  # not on Linux
        return os.cpu_count() or 1


def call(function, arguments):
    """What a worker runs: `function` on the arguments, each payload among them made a
    local file first."""
    return function(*resolve(arguments))


def _outcome(function, arguments):
    try:
        return function(*arguments)
    except Exception as exc:  # a task that fails is reported, the others go on
        return Failure(f"{type(exc).__name__}: {exc}")


class Engine:
    """A Dask client on an existing or a local cluster, or the serial run (module
    docstring). Use it as a context manager; `stream` and `map` run tasks on it."""

    def __init__(self, scheduler=None, jobs=None, say=None):
        """say(text), if given, hears where the tasks run once a cluster is up."""
        if jobs is not None and jobs < 1:
            raise EngineError(f"--jobs {jobs}: give 1 or more worker processes")
        self.scheduler, self.jobs, self.say = scheduler, jobs, say
        self.client = self.cluster = None

    @property
    def serial(self):
        return self.scheduler is None and self.jobs == 1

    def __enter__(self):
        self.start()
        return self

    def __exit__(self, *exc):
        self.close()

    def start(self, tasks=None):
        """Connect, or start the local cluster (no more workers than `tasks`, if given;
        a single task runs in this process). ``stream`` starts it when first needed."""
        if self.serial or self.client is not None:
            return
        if self.scheduler is None and tasks is not None and tasks <= 1:
            return
        from distributed import Client, LocalCluster

        # the scheduler's and workers' own chatter stays out of a command's output
        for name in ("distributed", "tornado", "bokeh"):
            logging.getLogger(name).setLevel(logging.ERROR)
        if self.scheduler:
            started = time.monotonic()
            try:
                self.client = Client(self.scheduler, timeout=CONNECT_TIMEOUT,
                                     set_as_default=False)
            except (OSError, TimeoutError, ValueError) as error:
                raise EngineError(
                    f"cannot reach the Dask scheduler at {self.scheduler} (waited "
                    f"{time.monotonic() - started:.0f} s: {error}); start one with `dask "
                    f"scheduler` and give its address, e.g. tcp://HOST:8786") from None
            try:
                self.client.wait_for_workers(1, timeout=WORKER_TIMEOUT)
            except TimeoutError:
                self.close()
                raise EngineError(f"the Dask scheduler at {self.scheduler} has no worker after "
                                  f"{WORKER_TIMEOUT} s: start one with `dask worker "
                                  f"{self.scheduler}`") from None
        else:
            workers = min(self.jobs or cores(), tasks or math.inf)
            with _deaf_to_ctrl_c(), _quiet_workers():
                self.cluster = LocalCluster(n_workers=workers, threads_per_worker=1,
                                            processes=True, dashboard_address=":0",
                                            silence_logs=logging.ERROR)
            self.client = Client(self.cluster, set_as_default=False)
        try:
            self.check_versions()
        except EngineError:
            self.close()
            raise
        if self.say is not None:
            self.say(f"running on {self.describe()}")

    def check_versions(self):
        """Refuse the cluster if a worker has another version of the package than this
        client: its tasks would not be the same computation."""
        own = package_version()
        found = self.client.get_versions(packages=[DISTRIBUTION])["workers"]
        for address, info in sorted(found.items()):
            theirs = (info or {}).get("packages", {}).get(DISTRIBUTION)
            if theirs != own:
                raise EngineError(
                    f"the worker at {address} has {DISTRIBUTION} {theirs or 'not installed'}, "
                    f"this client {own}: install {DISTRIBUTION} {own} on every worker "
                    f"(pip install {DISTRIBUTION}=={own}) and restart it")

    def close(self):
        for part in (self.client, self.cluster):
            if part is not None:
                try:
                    part.close()
                except Exception:  # a cluster already gone has nothing to close
                    pass
        self.client = self.cluster = None

    @property
    def workers(self):
        """How many workers run tasks now (1 for the serial run)."""
        if self.client is None:
            return 1
        return len(self.client.scheduler_info(n_workers=-1)["workers"])

    @property
    def dashboard(self):
        """The Dask dashboard's address, when the scheduler serves one."""
        if self.client is None:
            return None
        services = self.client.scheduler_info(n_workers=0).get("services", {})
        # a local scheduler draws its dashboard only where bokeh is installed
        drawn = self.scheduler is not None or _has_bokeh()
        return self.client.dashboard_link if "dashboard" in services and drawn else None

    def describe(self):
        if self.client is None:
            return "in this process, one run after another"
        where = self.scheduler or "a local cluster"
        text = f"{self.workers} worker{'s' if self.workers != 1 else ''} of {where}"
        return text + (f"; dashboard {self.dashboard}" if self.dashboard else "")

    def stream(self, function, tasks):
        """Yields (index, result or Failure) of every task (a tuple of `function`'s
        arguments) as it finishes; tasks not yet finished are cancelled when the caller
        stops early (Ctrl-C)."""
        tasks = list(tasks)
        self.start(len(tasks))
        if self.client is None:
            for index, arguments in enumerate(tasks):
                yield index, _outcome(function, resolve(arguments))
            return
        from distributed import as_completed

        futures = {self.client.submit(call, function, arguments, pure=False): index
                   for index, arguments in enumerate(tasks)}
        try:
            for future in as_completed(list(futures), loop=self.client.loop):
                index = futures.pop(future)
                if future.status == "error":
                    error = future.exception()
                    yield index, Failure(f"{type(error).__name__}: {error}")
                else:
                    yield index, future.result()
                future.release()
        finally:
            if futures:
                self.client.cancel(list(futures))

    def map(self, function, tasks):
        """Every task's result (or Failure) in the tasks' order."""
        tasks = list(tasks)
        results = [None] * len(tasks)
        for index, result in self.stream(function, tasks):
            results[index] = result
        return results


@contextmanager
def _deaf_to_ctrl_c():
    """Ctrl-C reaches every process of the terminal's group: the local workers, started
    in here, inherit SIGINT ignored, so that only this process answers it (it ends them)
    and no worker prints a traceback of its own."""
    if threading.current_thread() is not threading.main_thread():
        yield
        return
    previous = signal.signal(signal.SIGINT, signal.SIG_IGN)
    try:
        yield
    finally:
        signal.signal(signal.SIGINT, previous)


# The local workers' loggers, which a worker process sets up from its environment as it
# starts: at a Ctrl-C's shutdown a worker's heartbeat may meet the scheduler already closed,
# which distributed logs as an ERROR with a traceback, into the command's output. A task's
# own error reaches the client through its future, not the log.
QUIET_WORKERS = {"DASK_LOGGING__DISTRIBUTED": "critical"}


@contextmanager
def _quiet_workers():
    """The local workers started in here log only what is critical."""
    kept = {name: os.environ.get(name) for name in QUIET_WORKERS}
    os.environ.update(QUIET_WORKERS)
    try:
        yield
    finally:
        for name, value in kept.items():
            if value is None:
                os.environ.pop(name, None)
            else:
                os.environ[name] = value


def _has_bokeh():
    try:
        import bokeh  # noqa: F401
    except ImportError:
        return False
    return True


class Progress:
    """done/total and the time left: a bar on a terminal, a line every tenth in a log."""

    def __init__(self, total, done=0, what="runs"):
        from tqdm import tqdm

        self.total, self.done, self.what = total, done, what
        self.bar = tqdm(total=total, initial=done, desc=what, unit="run", file=sys.stderr,
                        disable=None)
        self.started, self.first = time.monotonic(), done
        self.next_line = done + max(1, total // 10)

    def update(self, label=""):
        self.done += 1
        self.bar.set_postfix_str(label)
        self.bar.update(1)
        if self.bar.disable and (self.done >= self.next_line or self.done == self.total):
            self.next_line = self.done + max(1, self.total // 10)
            print(f"{self.what}: {self.done}/{self.total} done{self._left()}", file=sys.stderr,
                  flush=True)

    def _left(self):
        ran = self.done - self.first
        if ran == 0 or self.done >= self.total:
            return ""
        rate = (time.monotonic() - self.started) / ran
        return f", about {rate * (self.total - self.done):.0f} s left"

    def close(self):
        self.bar.close()
