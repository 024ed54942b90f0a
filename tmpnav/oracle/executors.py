"""Where oracle evaluations run: in this process, in local worker processes, or on Ray.

The requests are cut into the same blocks whatever the executor, and each result depends
only on its own request, so every executor returns bit-identical results. Ray stays an
optional dependency (``pip install tmpnav[ray]``) and is imported only here.

Local workers never outlive the process that started them, however it ends: on Linux the
operating system kills them when it dies (``PR_SET_PDEATHSIG``, SIGKILL included), elsewhere a
watchdog thread in each worker notices that its parent is gone. An exception in the parent
while they compute (Ctrl-C's KeyboardInterrupt, the command line's SIGTERM,
tmpnav.lifetime.Terminated) terminates them before it propagates. No signal handler here:
one that shut the pool down could run while the interrupted code held the pool's lock.
"""

from __future__ import annotations

import contextlib
import ctypes
import functools
import multiprocessing
import os
import signal
import sys
import threading
import time
import weakref
from collections.abc import Callable, Iterator
from concurrent.futures import Future, ProcessPoolExecutor
from dataclasses import dataclass
from typing import Any

from tmpnav.errors import InputError
from tmpnav.lifetime import first_done, signals_held
from tmpnav.oracle.evaluate import EvalStats, Request, evaluate
from tmpnav.oracle.motions import MotionLibrary
from tmpnav.types import MotionResult, Roadmap, Scenario
from tmpnav.world import World
from tmpnav.world.build import Learned

Progress = Callable[[int, int], None]
Outcome = tuple[list[MotionResult | None], EvalStats]
#: a worker's outcome, the cells its world computed for it (World.take_new), and the worker's
#: process id with the entries of its wave's news it has taken (:class:`News`)
Work = tuple[Outcome, Learned, tuple[int, int]]

#: requests per block: large enough that per-task overhead (Ray: ~1 ms) is negligible
BLOCK = 64


@dataclass(frozen=True, eq=False)
class OracleContext:
    """Everything an evaluation needs, picklable for worker processes and Ray."""

    scenario: Scenario
    world: World
    roadmap: Roadmap

    @functools.cached_property
    def library_key(self) -> tuple[str, ...]:
        """What a motion library and the clocks on it read: the world, the roadmap and the whole
        scenario (its goals' windows and service times, its cost weights, not only its models
        and robots)."""
        return (self.world.fingerprint, self.roadmap.fingerprint, repr(self.scenario))


_LIBRARIES: dict[tuple[str, ...], MotionLibrary] = {}


def library(ctx: OracleContext) -> MotionLibrary:
    """The per-process motion library of a context (nominal motions are memoised in it).

    Keyed by content, so a Ray worker that receives the same context again reuses it; a new
    context takes from the library before what holds for it too (MotionLibrary.inherit). The
    key is the whole scenario: a library kept for a scenario with other goals gave the team's
    clock those goals (lib.scenario), so one process planning two goal sets on one map gave the
    second plan another plan than a process of its own.
    """
    key = ctx.library_key
    if key not in _LIBRARIES:
        before = list(_LIBRARIES.values())
        _LIBRARIES.clear()
        made = _LIBRARIES[key] = MotionLibrary(ctx.scenario, ctx.world, ctx.roadmap)
        for other in before:  # a replan's library takes what the one before computed (MotionLibrary.inherit)
            made.inherit(other)
    return _LIBRARIES[key]


def blocks(requests: list[Request], size: int | None = None) -> tuple[list[list[Request]], list[int]]:
    """Cut requests into blocks of whole start groups (about ``size`` requests each).

    Requests whose robots start from the same states share their simulations' prefixes,
    so a group is never split. Returns the blocks and the permutation that restores the
    requests' order (``order[k]`` is the original index of the k-th request in the blocks).
    """
    size = size or BLOCK
    groups: dict[tuple, list[int]] = {}
    for i, r in enumerate(requests):
        groups.setdefault((r.robots, r.starts, r.joint_cov), []).append(i)
    out: list[list[Request]] = []
    order: list[int] = []
    current: list[int] = []
    for members in groups.values():
        current.extend(members)
        if len(current) >= size:
            out.append([requests[i] for i in current])
            order.extend(current)
            current = []
    if current:
        out.append([requests[i] for i in current])
        order.extend(current)
    return out, order


def _merge(parts: list[Outcome], order: list[int]) -> Outcome:
    results: list[MotionResult | None] = [None] * len(order)
    stats = EvalStats()
    k = 0
    for res, st in parts:
        for r in res:
            results[order[k]] = r
            k += 1
        stats.add(st)
    return results, stats


class SerialExecutor:
    name = "serial"
    workers = 1

    def run(self, ctx: OracleContext, requests: list[Request], progress: Progress | None = None) -> Outcome:
        lib = library(ctx)
        parts = []
        todo, order = blocks(requests)
        for k, block in enumerate(todo):
            parts.append(evaluate(lib, block))
            if progress:
                progress(k + 1, len(todo))
        return _merge(parts, order)

    def let_go(self) -> None:
        return None

    def close(self) -> None:
        return None


_WORKER_CTX: OracleContext | None = None

#: prctl(2) option: the signal a process gets when its parent dies (Linux)
PR_SET_PDEATHSIG = 1
#: seconds between two checks of the watchdog that ends a worker whose parent is gone
WATCHDOG_PERIOD = 1.0


def die_with_parent(parent: int, use_prctl: bool = True) -> None:
    """Make this worker process end when ``parent`` does, however the parent ends."""
    if use_prctl and sys.platform.startswith("linux"):
        with contextlib.suppress(OSError, AttributeError):
            ctypes.CDLL(None, use_errno=True).prctl(PR_SET_PDEATHSIG, signal.SIGKILL, 0, 0, 0)
    if os.getppid() != parent:  # the parent died before the kernel was told
        os._exit(1)
    threading.Thread(target=_watch_parent, args=(parent,), name="tmpnav-parent-watchdog", daemon=True).start()


#: prctl(2) option: the name of the calling thread, the process's as ps and top show it (Linux)
PR_SET_NAME = 15


def name_process(name: str) -> None:
    """Call this (single-threaded, forked) process ``name`` (15 bytes at most) where ps, top and
    /proc/PID/comm show it, so that a run's oracle workers and its bound's process are told
    from the command itself (benchmarks/bench_fleet_memory.py counts their memory apart)."""
    if sys.platform.startswith("linux"):
        with contextlib.suppress(OSError, AttributeError):
            ctypes.CDLL(None).prctl(PR_SET_NAME, ctypes.c_char_p(name.encode()[:15]), 0, 0, 0)


def _watch_parent(parent: int) -> None:
    """The fallback where prctl is missing: a worker whose parent is gone is re-parented."""
    while os.getppid() == parent:
        time.sleep(WATCHDOG_PERIOD)
    os._exit(1)


def _init_worker(ctx: OracleContext, parent: int) -> None:
    global _WORKER_CTX
    # a SIGTERM handler the parent had came along with the fork: a worker just ends
    signal.signal(signal.SIGTERM, signal.SIG_DFL)
    # Ctrl-C is the parent's business (it cancels the pool); workers stay quiet
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    # held while the parent forked (tmpnav.lifetime.signals_held), and a fork keeps the mask: a
    # worker that blocked SIGTERM ignored the terminate of a stopped wave, 5 s each till killed
    signal.pthread_sigmask(signal.SIG_UNBLOCK, {signal.SIGTERM})
    die_with_parent(parent)
    name_process("tmpnav-oracle")
    ctx.world.take_new()  # what the parent computed before the fork, the parent has
    _WORKER_CTX = ctx


@dataclass(frozen=True)
class News:
    """The cells a wave's finished blocks computed that the parent did not know (World.learn
    returns them), entries ``start`` on of the wave's log. Each worker computes the reach and
    scan cells of its own blocks; without the news each computed most of the other's again
    (office 100 x 16: 196,000 scan keys computed for 107,000 distinct ones). A worker that
    missed entries computes their cells itself: the same values, only later."""

    wave: int
    start: int
    entries: tuple[Learned, ...]


#: the wave whose news a worker last took, and how many entries of its log it has taken
_TAKEN = [-1, 0]


def _take_news(world: World, news: News) -> int:
    """Put the entries of ``news`` the worker has not taken into its world; how many of the
    wave's entries it has taken now."""
    wave, taken = _TAKEN
    if wave != news.wave:
        taken = 0
    for entry in news.entries[max(taken - news.start, 0) :]:
        world.learn(entry)
    _TAKEN[:] = [news.wave, max(taken, news.start + len(news.entries))]
    return _TAKEN[1]


def _work(block: list[Request], news: News) -> Work:
    """A block's outcome, and the reach and scan cells computed for it, which the parent takes
    (World.learn) rather than compute them again for the requests it evaluates itself, and
    hands on to the other workers (:class:`News`). The memory the block's work freed goes back
    to the system (:func:`release_freed`)."""
    assert _WORKER_CTX is not None
    taken = _take_news(_WORKER_CTX.world, news)
    outcome = evaluate(library(_WORKER_CTX), block)
    learned = _WORKER_CTX.world.take_new()
    release_freed()
    return outcome, learned, (os.getpid(), taken)


def release_freed() -> None:
    """Give the heap's free pages back to the system (glibc's ``malloc_trim``; elsewhere nothing).

    A block's simulations allocate and free hundreds of MB in pieces; glibc keeps the freed
    pages, so a worker's resident size was its largest block's, not what it holds (100 MB more
    a worker at office 100 x 16; about 1 ms a block)."""
    if sys.platform.startswith("linux"):
        with contextlib.suppress(OSError, AttributeError):
            ctypes.CDLL(None).malloc_trim(0)


#: seconds a pool of workers may stand idle before they are let go (:class:`ProcessExecutor`)
IDLE_SECONDS = 3.0
#: blocks per worker submitted at a time: a worker's next block waits for it when it finishes
#: one, and a block submitted later carries the news of the blocks finished before (:class:`News`)
QUEUED = 2


class ProcessExecutor:
    """Local worker processes (``--workers N``); the context is sent once per worker.

    The pool lives from one wave of requests to the next, so the nominal motions a worker
    computed for one wave (singles, then pairs) are still in its memory for the next. A pool
    that no wave has used for :data:`IDLE_SECONDS` is let go: a fleet's run asks its workers
    for the single moves' table and then, through the search, for one move at a time, which
    this process computes itself, and the idle workers held their tables and motions (1 GB at
    office 100 x 16) to the end. The next wave forks new workers, which share this process's
    pages; the results do not depend on which workers compute them.
    """

    name = "processes"

    def __init__(self, workers: int, idle_seconds: float | None = None):
        self.workers = workers
        self.idle_seconds = IDLE_SECONDS if idle_seconds is None else idle_seconds
        self._pool: ProcessPoolExecutor | None = None
        self._ctx: OracleContext | None = None
        self._lock = threading.Lock()  # a wave, or letting the pool go: one at a time
        self._idle: threading.Timer | None = None
        #: pools started so far (one, unless an idle pool was let go and a later wave needed one)
        self.started = 0
        self._waves = 0

    def _get_pool(self, ctx: OracleContext) -> ProcessPoolExecutor:
        if self._pool is None or self._ctx is not ctx:
            self._shut()
            method = "fork" if "fork" in multiprocessing.get_all_start_methods() else "spawn"
            mp = multiprocessing.get_context(method)
            self._pool = ProcessPoolExecutor(
                self.workers, mp_context=mp, initializer=_init_worker, initargs=(ctx, os.getpid())
            )
            self._ctx = ctx
            self.started += 1
        return self._pool

    def run(self, ctx: OracleContext, requests: list[Request], progress: Progress | None = None) -> Outcome:
        todo, order = blocks(requests)
        if len(todo) <= 1:
            return SerialExecutor().run(ctx, requests, progress)
        with self._lock:
            self._cancel_idle()
            outcome = self._wave(ctx, todo, order, progress)
            if self._pool is not None:
                self._idle = threading.Timer(self.idle_seconds, self._let_go_idle)
                self._idle.daemon = True
                self._idle.start()
        return outcome

    def _let_go_idle(self) -> None:
        """The idle timer's end: the workers are let go unless a wave has begun since (it
        holds the lock, and arms a timer of its own when it ends)."""
        if self._lock.acquire(blocking=False):
            try:
                if self._idle is threading.current_thread():
                    self._idle = None
                    self._shut()
            finally:
                self._lock.release()

    def _wave(
        self, ctx: OracleContext, todo: list[list[Request]], order: list[int], progress: Progress | None
    ) -> Outcome:
        pool = self._get_pool(ctx)
        self._waves += 1
        log: list[Learned] = []  # the wave's news (:class:`News`)
        taken: dict[int, int] = {}  # the entries of the log each worker (process id) has taken
        parts: list[Outcome | None] = [None] * len(todo)
        running: dict[Future[Work], int] = {}
        sent = done = 0
        try:
            while done < len(todo):
                while sent < len(todo) and len(running) < QUEUED * self.workers:
                    start = min(taken.values(), default=0)
                    with signals_held():  # the first blocks fork the workers
                        running[pool.submit(_work, todo[sent], News(self._waves, start, tuple(log[start:])))] = sent
                    sent += 1
                for future in first_done(running):
                    part, learned, (pid, entries) = future.result()
                    parts[running.pop(future)] = part
                    taken[pid] = entries
                    if fresh := ctx.world.learn(learned):
                        log.append(fresh)
                    done += 1
                    if progress:
                        progress(done, len(todo))
        except BaseException:
            self._terminate()  # Ctrl-C or a failure: do not wait for the blocks under way
            raise
        return _merge([p for p in parts if p is not None], order)

    def _terminate(self) -> None:
        """Stop the workers now (cancelling queued blocks) and reap them."""
        pool, self._pool = self._pool, None
        if pool is None:
            return
        # ProcessPoolExecutor has no public way to stop running tasks before Python 3.14
        workers = list(getattr(pool, "_processes", {}).values())
        _quiet(getattr(pool, "_executor_manager_thread", None))
        for process in workers:
            with contextlib.suppress(OSError, ValueError):
                process.terminate()
        pool.shutdown(wait=False, cancel_futures=True)
        for process in workers:
            with contextlib.suppress(OSError, ValueError, AssertionError):
                process.join(timeout=5)
                if process.is_alive():
                    process.kill()

    def _cancel_idle(self) -> None:
        if self._idle is not None:
            self._idle.cancel()
            self._idle = None

    def _shut(self) -> None:
        if self._pool is not None:
            self._pool.shutdown()
            self._pool = None

    def let_go(self) -> None:
        """Let the workers go now: the caller knows that no wave is near (a later one forks new
        workers, as after :data:`IDLE_SECONDS`)."""
        self.close()

    def close(self) -> None:
        with self._lock:
            self._cancel_idle()
            self._shut()


#: threads whose exceptions are not printed (:func:`_quiet`)
_QUIET: weakref.WeakSet[threading.Thread] = weakref.WeakSet()


def _quiet(thread: threading.Thread | None) -> None:
    """Print no exception of ``thread``: the pool's manager thread, whose workers are being
    terminated, can trip over their pipes closing (seen once as a traceback on stderr after
    Ctrl-C, tests/oracle/test_cache.py). The run is ending, and says why itself. One hook reads
    the set, put before the hook in place unless it is already there."""
    if thread is None:
        return
    if not getattr(threading.excepthook, "tmpnav_quiet", False):
        previous = threading.excepthook

        def hook(args: threading.ExceptHookArgs) -> None:
            if args.thread not in _QUIET:
                previous(args)

        hook.tmpnav_quiet = True  # type: ignore[attr-defined]
        threading.excepthook = hook
    _QUIET.add(thread)


class RayExecutor:
    """The same blocks as Ray tasks on a local or remote cluster (``--executor ray``)."""

    name = "ray"

    def __init__(self, address: str | None = None, num_cpus: int | None = None):
        try:
            import ray
        except ImportError:
            raise InputError("--executor ray needs Ray: pip install 'tmpnav[ray]'") from None
        self._ray = ray
        self._started = False
        if not ray.is_initialized():
            kwargs: dict[str, Any] = {"ignore_reinit_error": True, "log_to_driver": False, "include_dashboard": False}
            if address:
                kwargs["address"] = address
            else:
                kwargs["num_cpus"] = num_cpus or os.cpu_count() or 1
            try:
                with signal_handlers_kept():
                    ray.init(**kwargs)
            except (ConnectionError, RuntimeError, ValueError) as err:
                raise InputError(f"cannot start or reach Ray at {address or 'a new local instance'}: {err}") from None
            self._started = True
        self.workers = int(ray.cluster_resources().get("CPU", 1))
        self._remote = ray.remote(_ray_work)

    def run(self, ctx: OracleContext, requests: list[Request], progress: Progress | None = None) -> Outcome:
        ray = self._ray
        ctx_ref = ray.put(ctx)
        todo, order = blocks(requests)
        pending = [self._remote.remote(ctx_ref, block) for block in todo]
        index = {ref: k for k, ref in enumerate(pending)}
        parts: list[Outcome | None] = [None] * len(pending)
        done = 0
        remaining = list(pending)
        while remaining:
            ready, remaining = ray.wait(remaining, num_returns=1)
            for ref in ready:
                parts[index[ref]] = ray.get(ref)
                done += 1
                if progress:
                    progress(done, len(todo))
        return _merge([p for p in parts if p is not None], order)

    def let_go(self) -> None:
        return None  # the cluster's workers are the cluster's

    def close(self) -> None:
        if self._started:
            with signal_handlers_kept():
                self._ray.shutdown()


#: the signals whose handlers Ray's start and shutdown replace in the calling process
#: (SIGABRT, SIGBUS, SIGFPE, SIGILL, SIGSEGV, SIGTERM; measured with Ray 2.60)
KEPT_SIGNALS = (signal.SIGABRT, signal.SIGBUS, signal.SIGFPE, signal.SIGILL, signal.SIGSEGV, signal.SIGTERM)


class _SigAction(ctypes.Structure):
    """glibc's ``struct sigaction`` (Linux, x86_64 and aarch64)."""

    _fields_ = (
        ("handler", ctypes.c_void_p),
        ("mask", ctypes.c_ulong * 16),
        ("flags", ctypes.c_int),
        ("restorer", ctypes.c_void_p),
    )


@contextlib.contextmanager
def signal_handlers_kept() -> Iterator[None]:
    """The process's own handlers of :data:`KEPT_SIGNALS` put back after the block (Linux).

    ``ray.init`` installs Ray's crash handlers for them in the calling process, and
    ``ray.shutdown`` resets most to the default: tmpnav's own SIGTERM handling
    (tmpnav.lifetime) was Ray's, and while ENHSP's JVM ran inside tmpnav (until 2026-11-28;
    it takes SIGSEGV, SIGBUS, SIGFPE and SIGILL in its normal work) the next such signal
    ended the process (the test suite's worker died in the anytime search after a test ran
    Ray). The handlers are kept at the C level, where a library's own are."""
    saved = signal_actions()
    try:
        yield
    finally:
        libc = ctypes.CDLL(None)
        for sig, action in saved.items():
            libc.sigaction(int(sig), ctypes.byref(action), None)


def signal_actions() -> dict[signal.Signals, _SigAction]:
    """The C-level action of each of :data:`KEPT_SIGNALS` now (Linux; elsewhere none)."""
    if not sys.platform.startswith("linux"):
        return {}
    libc = ctypes.CDLL(None)
    saved = {}
    for sig in KEPT_SIGNALS:
        action = _SigAction()
        if libc.sigaction(int(sig), None, ctypes.byref(action)) == 0:
            saved[sig] = action
    return saved


def _ray_work(ctx: OracleContext, block: list[Request]) -> Outcome:
    return evaluate(library(ctx), block)


def make_executor(kind: str, workers: int | None = None, ray_address: str | None = None) -> Any:
    """``serial``, ``processes`` (default when workers > 1) or ``ray``."""
    if kind == "ray":
        return RayExecutor(ray_address, workers)
    n = workers if workers is not None else (os.cpu_count() or 1)
    if kind == "serial" or n <= 1:
        return SerialExecutor()
    if kind == "processes":
        return ProcessExecutor(n)
    raise InputError(f"unknown executor {kind!r}; expected serial, processes or ray")
