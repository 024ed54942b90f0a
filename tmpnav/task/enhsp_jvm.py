"""ENHSP in one JVM inside the tmpnav process (JPype): a JVM start per run, not per solve.

up_enhsp runs ``java -jar enhsp.jar`` for every solve, about 0.3 s of JVM start each; the
anytime search solves dozens of small sub-problems, most of which ENHSP itself plans in a
few milliseconds. Here the JVM starts once, on the first solve, with the Java that
:func:`tmpnav.java.find` chooses, and each solve calls ENHSP's command-line entry point
(``main.main``) with the arguments up_enhsp's engine builds: still ENHSP, the same search,
the same plan file, read by :mod:`tmpnav.task.solve` as before.

What a shared JVM changes, and how this module keeps the old behaviour:

- Lifetime: the JVM is part of this process, so it ends with it, however the run ends.
  ``-Xrs`` keeps the JVM's hands off SIGINT and SIGTERM (tmpnav.lifetime's handlers stay).
  The thread that starts the JVM becomes its non-daemon "main", which JPype's shutdown at
  Python's exit waits for: it is the caller's thread (tmpnav.task.solve.side_by_side starts
  the JVM before its searching threads), never a search's, which a signal may leave behind.
- Static state: ENHSP keeps registries in static fields (interned predicates, fluents,
  objects, types, transition ids) and never resets them: reused as they are, they gave other
  plans than a fresh process, and a wrong "unsolvable", once the domain changed. So each
  concurrent solve has its own *slot*, ENHSP in a class loader of its own, whose classes are
  all loaded at once and their static fields recorded; before every solve the slot puts them
  back as they were (null, a number, or a collection's first contents). A slot with a field
  of another kind would not be reused (a new slot per solve: about 190 ms instead of 20 ms).
  Both are tmpnav's one Java class (java/EnhspSlot.java, shipped compiled beside it and put
  on the JVM's class path), one call each outside Python's lock, so that a slot made ready in
  the background does not wait for the main thread, nor slow it down, thousands of times.
- Exit: the JVM is destroyed at Python's exit (JPype's shutdown). A thread still inside it
  then is stopped there for good, which deadlocked (holding Python's lock) or crashed the
  process, so :func:`quiesce` first stops the searches and waits for this module's threads
  (the warm-up's, the searches'), and every thread that called into the JVM detaches before
  it ends (:func:`detach`: the JVM's exit waited 0.3 s for each one left attached).
- Warm-up: :func:`warm` loads the slots the search will use, and runs a small search in
  each, in a background thread while the run computes its first plan.
- Output: ENHSP prints its log on the JVM's one ``System.out``, which two solves at once
  would share; it goes nowhere. A crash is a Java exception, whose text is the log tail.
- ``System.gc()``: ENHSP asks for a full collection per run; ``-XX:+DisableExplicitGC``.
- Time limit: ENHSP has none of its own. A solve runs in a thread of its own; at the limit
  the thread is stopped (``Thread.stop``, which Java 17-19 still honour). Where the JVM
  refuses (Java 20+), the search cannot be stopped: the JVM is then not used again in this
  run (the process path takes over) and the stray search ends with the process.
- ``System.exit``: ENHSP calls it on a bad command line (ours is up_enhsp's), and its PDDL
  library (libs/JPddl_.jar) in about a dozen classes (conditions, expressions) on errors;
  tmpnav's generated PDDL has not reached them (the tests; every sub-problem of a 10-room
  run). If one did, the tmpnav process would end. Refusing it needs a SecurityManager, a
  compiled subclass JPype cannot make (and Java 24+ has none).

Only this module imports JPype. ``TMPNAV_ENHSP=process`` turns it off.
"""

from __future__ import annotations

import atexit
import contextlib
import importlib.util
import os
import queue
import shlex
import sys
import tempfile
import threading
import time
from collections.abc import Callable, Iterator
from dataclasses import dataclass
from pathlib import Path
from typing import Literal

#: environment variable choosing how ENHSP runs: "jvm" (the default) or "process"
MODE_ENV = "TMPNAV_ENHSP"
#: tmpnav's Java class (java/EnhspSlot.java, built by ``make java``), on the JVM's class path
HELPER_JAR = Path(__file__).parent / "java" / "tmpnav-enhsp.jar"
#: JVM options always added: signals stay Python's (tmpnav.lifetime), ENHSP's System.gc()
#: per run is not a full collection of the shared heap
FIXED_OPTIONS = ("-Xrs", "-XX:+DisableExplicitGC")
#: the first Java that knows --enable-native-access (and from 22 on, warns without it)
NATIVE_ACCESS_JAVA = 21
#: seconds a stopped search has to end before the JVM is given up for the run
STOP_GRACE = 2.0
#: seconds between looks at whether a search was asked to stop (:func:`stop_all`)
POLL = 0.05
#: seconds the small search that warms a slot may take (:func:`warm`; it takes about 0.2 s)
WARM_TIMEOUT = 10.0
#: seconds the end of a run waits for threads to leave the JVM (:func:`quiesce`); a slot's
#: classes load in about 0.3 s, a stopped search ends in milliseconds
QUIESCE_SECONDS = 2.0


@dataclass(frozen=True)
class JvmRun:
    """What one ENHSP run in the JVM did: finished, or stopped at its time limit; the text
    of the Java exception it ended with, if any."""

    timed_out: bool
    error: str | None = None


class _Slot:
    """ENHSP in a class loader of its own over enhsp.jar: its ``main``, and the first values
    of ENHSP's static fields, put back before every solve (:meth:`reset`). The loading, the
    recording and the putting back are tmpnav's Java class (java/EnhspSlot.java), each one
    call into the JVM: see that file for why not JPype's reflection from Python."""

    def __init__(self, jar: str) -> None:
        import jpype

        self.java = jpype.JClass("tmpnav.EnhspSlot")(jar)
        self.main = jpype.JClass(self.java.load("main"))
        for archive, prefixes in _own_classes(jar):
            self.java.record(archive, prefixes)
        self.reusable = bool(self.java.reusable())

    def reset(self) -> None:
        """ENHSP's static fields as they were when its classes were loaded."""
        self.java.reset()

    def close(self) -> None:
        self.java.close()


def _own_classes(jar: str) -> tuple[tuple[str, list[str]], ...]:
    """ENHSP's own classes, each archive with the prefixes of their paths: enhsp.jar's, and
    those of its PDDL library (libs/JPddl_.jar), whose static fields hold its state; the other
    libraries are generic (collections, parser runtime)."""
    library = os.path.join(os.path.dirname(jar), "libs", "JPddl_.jar")
    return ((jar, ["main.", "planners/"]), (library, ["com/hstairs/"]))


class _Jvm:
    """The process's one JVM: started on first use; ``broken`` says why it is not used."""

    def __init__(self) -> None:
        self.lock = threading.Lock()
        self.started = False
        self.broken: str | None = None
        self.jar = ""
        self.slots: queue.LifoQueue[_Slot] = queue.LifoQueue()  # idle, reset before each use
        self.warming: threading.Thread | None = None  # getting slots ready (:func:`warm`)
        self.closing = threading.Event()  # the run is ending (:func:`quiesce`): warm nothing more

    def ready(self, options: str) -> bool:
        """Start the JVM (with JVM ``options``) if it has not started; False (and ``broken``
        set) if it cannot."""
        with self.lock:
            if not self.started and self.broken is None:
                try:
                    self.jar = _start(options)
                    self.started = True
                    # at Python's exit, before JPype's shutdown (registered earlier, so run later)
                    atexit.register(quiesce, QUIESCE_SECONDS)
                except Exception as err:  # any failure to start means: use processes
                    self.broken = f"the JVM did not start: {err}"
            return self.started and self.broken is None


_JVM = _Jvm()
#: the threads that may be inside the JVM now, besides the main thread (:func:`quiesce`)
_threads: set[threading.Thread] = set()
_threads_lock = threading.Lock()
#: the runs in progress, each by the event that stops it (:func:`stop_all`)
_stops: set[threading.Event] = set()
_stops_lock = threading.Lock()


def stop_all() -> None:
    """Stop every search running in the JVM now (a signal is ending the run): each
    :func:`run` asks its search's thread to stop and returns at once, as timed out, without
    the grace :func:`_stop` gives a search at its time limit (on Java 20+, which cannot stop
    a thread, that grace held a Ctrl-C 2 s; the search then ends with the process)."""
    with _stops_lock:
        for stop in _stops:
            stop.set()


def forced_process() -> bool:
    """Whether ``TMPNAV_ENHSP=process`` asks for a ``java`` process per solve."""
    return os.environ.get(MODE_ENV, "").strip().lower() == "process"


def unavailable() -> str | None:
    """Why ENHSP runs as a process per solve here (None: it runs in the shared JVM)."""
    if forced_process():
        return f"{MODE_ENV}=process"
    try:
        import jpype  # noqa: F401
    except ImportError:
        return "JPype (the JPype1 package) is not installed"
    if _JVM.broken is not None:
        return _JVM.broken
    if libjvm() is None:
        return "the Java that runs ENHSP has no lib/server/libjvm.so"
    return None


def usable(options: str) -> bool:
    """Whether this solve can run in the shared JVM (starting it now, with the JVM options
    ``options``, if need be)."""
    return unavailable() is None and _JVM.ready(options)


def describe() -> str:
    """For ``tmpnav doctor``'s Java line: how ENHSP runs, and why."""
    reason = unavailable()
    if reason is None:
        return "in one JVM for the run inside tmpnav (JPype)"
    return f"in a JVM process per solve ({reason})"


def libjvm() -> Path | None:
    """The JVM library of the Java that runs ENHSP (tmpnav.java.find), or None."""
    from tmpnav.java import find

    java = find()
    if java is None:
        return None
    home = Path(os.path.realpath(java.executable)).parent.parent
    for candidate in (home / "lib" / "server" / "libjvm.so", home / "jre" / "lib" / "server" / "libjvm.so"):
        if candidate.is_file():
            return candidate
    return None


def enhsp_jar() -> str:
    """The path of up_enhsp's enhsp.jar (its ``ENHSP_JAR``), found without importing up_enhsp."""
    spec = importlib.util.find_spec("up_enhsp")
    if spec is None or not spec.submodule_search_locations:
        raise RuntimeError("up_enhsp is not installed")
    return os.path.join(next(iter(spec.submodule_search_locations)), "ENHSP", "enhsp.jar")


def _start(options: str) -> str:
    """Start the JVM with ENHSP's JVM ``options``; return the path of enhsp.jar."""
    import jpype

    from tmpnav.java import find

    path, java = libjvm(), find()
    if path is None or java is None:
        raise RuntimeError("no libjvm.so")
    # Java 22+ warns on stderr, 4 lines, when JPype loads its native part; this allows it
    native = ("--enable-native-access=ALL-UNNAMED",) if java.version >= NATIVE_ACCESS_JAVA else ()
    # JNI_CreateJavaVM also reads JAVA_TOOL_OPTIONS: solve_text starts the JVM before it
    # sets tmpnav's own there (solve.java_options), so they are not given twice
    with _stderr_held() as said:
        try:
            jpype.startJVM(
                str(path),
                *shlex.split(options),
                *FIXED_OPTIONS,
                *native,
                classpath=[str(HELPER_JAR)],
                interrupt=False,
                convertStrings=False,
            )
        except Exception as err:
            raise RuntimeError(" ".join(f"{err} {said()}".split())) from None
    system = jpype.JClass("java.lang.System")
    nowhere = jpype.JClass("java.io.PrintStream")(jpype.JClass("java.io.OutputStream").nullOutputStream())
    system.setOut(nowhere)  # ENHSP's log: see the module's docstring
    system.setErr(nowhere)
    return enhsp_jar()


@contextlib.contextmanager
def _stderr_held() -> Iterator[Callable[[], str]]:
    """Hold what is written to file descriptor 2 inside (the JVM prints its start errors
    there, not as an exception): given back to stderr after a start, or kept in the error
    of a failed one, so that a bad JVM option is one line of tmpnav's, not two."""
    saved = os.dup(2)
    with tempfile.TemporaryFile() as held:
        os.dup2(held.fileno(), 2)

        def said() -> str:
            held.seek(0)
            return held.read().decode(errors="replace")

        failed = True
        try:
            yield said
            failed = False
        finally:
            os.dup2(saved, 2)
            os.close(saved)
            if not failed:
                sys.stderr.write(said())


def run(args: list[str], timeout: float) -> JvmRun:
    """Run ENHSP's ``main`` with ``args`` (up_enhsp's, without ``java -jar``) in the shared
    JVM, stopping it after ``timeout`` seconds. Call :func:`usable` first."""
    with _inside():
        return _run_in(_take(), args, timeout)


@contextlib.contextmanager
def _inside() -> Iterator[None]:
    """The calling thread may call into the JVM inside (:func:`quiesce` waits for it); not
    the main thread, which shuts the JVM down itself."""
    me = threading.current_thread()
    if me is threading.main_thread():
        yield
        return
    with _threads_lock:
        _threads.add(me)
    try:
        yield
    finally:
        with _threads_lock:
            _threads.discard(me)


def quiesce(timeout: float) -> bool:
    """Before the JVM is shut down: stop what runs in it (the warm-up, the searches) and wait up
    to ``timeout`` seconds for every thread of this module to leave it. True when none is left.

    A thread inside the JVM when it is destroyed (JPype's shutdown at Python's exit) is stopped
    at the JVM's last safepoint for good: holding Python's lock (a JNI call from Python code,
    such as freeing a Java object), it deadlocked the main thread, which needs that lock back
    after DestroyJavaVM; running compiled Java code, it crashed the process at a safepoint
    poll (seen in the test suite: a run interrupted while the warm-up loaded ENHSP). The
    command line ends the process without destroying the JVM when this returns False
    (tmpnav.__main__); at Python's exit, it runs before JPype's shutdown (registered when
    the JVM starts)."""
    _JVM.closing.set()
    stop_all()
    deadline = time.monotonic() + timeout
    with _threads_lock:
        threads = list(_threads)
    for thread in threads:
        thread.join(max(0.0, deadline - time.monotonic()))
    return not any(t.is_alive() for t in threads)


def not_destroyed_at_exit() -> None:
    """Let Python's exit leave the JVM as it is, for a process that ends right after it
    (``os._exit``: tmpnav.__main__) once :func:`quiesce` has seen every thread of this module
    leave the JVM. DestroyJavaVM waits up to 0.3 s for every thread that ever entered the JVM
    and ended without leaving it (HotSpot's VM_Exit), and a thread this module does not own
    can enter it unasked: Python's collector frees Java objects in whichever thread it runs,
    multiprocessing's included. Measured: 3 of 8 fresh 10-room runs ended with such a thread
    and spent 0.33 s in Python's exit instead of 0.01 s. The process's end frees what the JVM
    holds; no shutdown hook matters (ENHSP's plans are in their files by then, its output goes
    nowhere). Where Python itself finalizes after it (not tmpnav's command line), keep the
    default: a JVM left running there aborted the process (2026-11-25)."""
    if "jpype" in sys.modules:
        import jpype.config

        jpype.config.destroy_jvm = False


def detach() -> None:
    """Detach the calling thread from the JVM, where a Java call attached it (JPype attaches a
    thread on its first call and never detaches it), before the thread ends; never the JVM's
    main thread. A thread that ended attached stays "in native" for the JVM, whose shutdown
    (DestroyJavaVM at Python's exit) then waits 0.3 s for it to stop (HotSpot's VM_Exit waits
    up to 300 ms for such threads): measured, 0.32 s at the end of every run that solved once,
    0.01 s with the threads detached."""
    if threading.current_thread() is threading.main_thread() or "jpype" not in sys.modules:
        return
    import jpype

    if jpype.isJVMStarted() and jpype.java.lang.Thread.isAttached():
        jpype.java.lang.Thread.detach()


def warm(slots: int, sample: Callable[[], contextlib.AbstractContextManager[list[str]]]) -> None:
    """Get ``slots`` searches ready in a daemon thread while the caller goes on: ENHSP's classes
    loaded in a slot of its own for each, and one search of a small problem run in each
    (``sample``: a context giving ENHSP's arguments for it, its files kept while inside), so
    that the run's first searches do not pay for either. Measured on the 10-room corridor's 24
    sub-problems, one after another in a fresh process: the first took 0.79 s (JVM start
    0.25 s, a slot 0.32 s, its first search 0.2 s against 0.04 s warm), and all took 2.07 s
    cold against 1.11 s warm. Call after :func:`usable` has started the JVM (in the main
    thread, see the module docstring); slots already idle count (a second run in the process
    warms nothing). A search that finds no idle slot while the thread runs waits for the next
    one (:func:`_take`). At the run's end, :func:`quiesce` stops the thread's search and waits
    for it to leave the JVM; it makes no slot after that."""
    missing = slots - _JVM.slots.qsize()
    if missing <= 0 or not _JVM.started or _JVM.closing.is_set():
        return

    def ready() -> None:
        try:
            with _inside():
                _ready()
        finally:
            detach()

    def _ready() -> None:
        for _ in range(missing):
            if _JVM.closing.is_set():
                return
            try:
                slot = _Slot(_JVM.jar)
            except Exception:  # a search makes its own slot, and meets the same failure
                return
            if not slot.reusable:  # a slot that cannot be reused serves one search only
                slot.close()
                return
            if _JVM.closing.is_set():
                _JVM.slots.put(slot)
                return
            ran = False
            try:
                with sample() as args:
                    ran = True
                    _run_in(slot, args, WARM_TIMEOUT)  # gives the slot back when done
            except Exception:  # the sample's files: the slot is still good, and idle
                if not ran:
                    _JVM.slots.put(slot)

    thread = threading.Thread(target=ready, name="tmpnav-enhsp-warm", daemon=True)
    _JVM.warming = thread
    thread.start()


def settle(timeout: float) -> bool:
    """Wait up to ``timeout`` seconds for the searches :func:`warm` makes ready; True when none
    is being made any more (a benchmark's warm-up ends with its searches ready, as in a
    planning service that is already running: ``tmpnav.bench.worker``)."""
    warming = _JVM.warming
    if warming is not None:
        warming.join(timeout)
    return warming is None or not warming.is_alive()


def _take() -> _Slot:
    """An idle slot; one being made ready (:func:`warm`) when there is none; else a new one."""
    while True:
        try:
            return _JVM.slots.get_nowait()
        except queue.Empty:
            pass
        warming = _JVM.warming
        if warming is None or not warming.is_alive():
            return _Slot(_JVM.jar)
        with contextlib.suppress(queue.Empty):
            return _JVM.slots.get(timeout=POLL)


def _run_in(slot: _Slot, args: list[str], timeout: float) -> JvmRun:
    """Run ENHSP's ``main`` with ``args`` in ``slot``, given back to the idle ones after it."""
    slot.reset()
    done = threading.Event()
    box: dict[str, object] = {}

    def target() -> None:
        import jpype

        try:
            jpype.java.lang.Thread.attachAsDaemon()
            box["thread"] = jpype.java.lang.Thread.currentThread()
            try:
                slot.main.main(args)
            except Exception as err:  # a Java exception (or ThreadDeath after a stop)
                box["error"] = f"{type(err).__name__}: {err}"
        finally:
            done.set()
            detach()
            with _threads_lock:
                _threads.discard(threading.current_thread())

    thread = threading.Thread(target=target, name="tmpnav-enhsp", daemon=True)
    with _threads_lock:
        _threads.add(thread)
    thread.start()
    ended = _wait(done, timeout)
    if ended == "done":
        _JVM.slots.put(slot) if slot.reusable else slot.close()
        error = box.get("error")
        return JvmRun(False, None if error is None else str(error))
    if ended == "stopped":  # the run is ending: asked to stop, not waited for (see stop_all)
        _ask_to_stop(box.get("thread"))
    elif _stop(box.get("thread"), done):
        slot.close()
    return JvmRun(True)


def _wait(done: threading.Event, timeout: float) -> Literal["done", "limit", "stopped"]:
    """Wait for a search to end within ``timeout`` seconds: "done" if it did, "limit" if it
    did not, "stopped" at once when :func:`stop_all` is called."""
    stop = threading.Event()
    with _stops_lock:
        _stops.add(stop)
    try:
        deadline = time.monotonic() + timeout
        while not done.wait(min(POLL, max(deadline - time.monotonic(), 0.0))):
            if stop.is_set():
                return "stopped"
            if time.monotonic() >= deadline:
                return "limit"
        return "done"
    finally:
        with _stops_lock:
            _stops.discard(stop)


def _ask_to_stop(thread: object) -> None:
    """``Thread.stop`` a search's Java thread, not waiting for it (Java 20+ refuses: nothing)."""
    stop = getattr(thread, "stop", None)
    try:
        if stop is not None:
            stop()
    except Exception:  # Java 20+: UnsupportedOperationException
        pass


def _stop(thread: object, done: threading.Event) -> bool:
    """Stop a search past its time limit (True if it stopped); if the JVM cannot, stop
    using the JVM for the rest of the run."""
    _ask_to_stop(thread)
    if done.wait(STOP_GRACE):
        return True
    with _JVM.lock:
        _JVM.broken = "a search could not be stopped at its time limit (Java 20+ has no Thread.stop)"
    return False
