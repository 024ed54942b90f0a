"""ENHSP in one JVM for the run, a server process beside tmpnav: a JVM start per run, not per solve.

up_enhsp runs ``java -jar enhsp.jar`` for every solve, about 0.3 s of JVM start each; the
anytime search solves dozens of small sub-problems, most of which ENHSP itself plans in a
few milliseconds. Here one ``java`` process, started with the Java that
:func:`tmpnav.java.find` chooses, runs tmpnav's server (java/EnhspServer.java, shipped
compiled in java/tmpnav-enhsp.jar: ``make java``), and each solve calls ENHSP's command-line
entry point (``main.main``) in it with the arguments up_enhsp's engine builds: still ENHSP,
the same search, the same plan file, read by :mod:`tmpnav.task.solve` as before. Requests and
answers are lines on the server's standard input and output (see the Java file).

Why a process of its own (until 2026-11-28 the JVM ran inside tmpnav, through JPype): the
in-process JVM's start held the run's main thread for 0.2 s in every fresh ``tmpnav plan``
(JPype's start makes thousands of calls between Python and Java, each taking Python's lock);
each call from a searching thread waited for that lock while the main thread computed costs;
and JPype ran a full Python collection after each of the JVM's (tmpnav.heap). The server
starts beside the run (:func:`usable`: a process start, nothing waited for), readies its
searches while tmpnav loads its modules and grows its roadmap, and needs nothing of tmpnav's
lock but a line written and one read per solve.

What this module keeps from ENHSP's behaviour as a process per solve:

- Lifetime: the server ends when its input closes, that is when tmpnav ends, however it ends
  (a kill included: the kernel closes the pipe); it is in a session of its own, so a Ctrl-C
  at the terminal is tmpnav's to handle (tmpnav.lifetime), which closes it.
- Static state: ENHSP keeps registries in static fields and never resets them, so each
  concurrent solve has its own *slot*, ENHSP in a class loader of its own whose static fields
  are recorded when it is made and put back before every solve (java/EnhspSlot.java).
- Warm-up: :func:`warm` has the server make the slots the search will use, and run a small
  search in each, while the run computes its first costs, plan and bound.
- Output: ENHSP's log goes nowhere; a crash is a Java exception, whose text is the answer.
- Time limit: the server stops a search at its limit (``Thread.stop``, which Java 17-19 still
  honour). Where the JVM refuses (Java 20+), the search cannot be stopped: the server is not
  asked for another search in this run (the process path takes over), the searches under
  way end as they would, and the stray one ends with the server, at the run's end.
- ``System.exit``: ENHSP calls it on a bad command line (ours is up_enhsp's) and its PDDL
  library on some errors: the server ends, and the solves under way fail with what it said.

``TMPNAV_ENHSP=process`` turns it off: a ``java`` process per solve, as up_enhsp runs it.
"""

from __future__ import annotations

import atexit
import contextlib
import importlib.util
import itertools
import os
import shlex
import subprocess
import tempfile
import threading
import time
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path
from typing import IO, Literal

#: environment variable choosing how ENHSP runs: "jvm" (the default) or "process"
MODE_ENV = "TMPNAV_ENHSP"
#: JVM options always added: no signal handlers of the JVM's own (tmpnav ends it by closing
#: its input), ENHSP's System.gc() per run is not a full collection of the shared heap
FIXED_OPTIONS = ("-Xrs", "-XX:+DisableExplicitGC")
#: tmpnav's Java classes (java/*.java, built by ``make java``): the server and its slots
HELPER_JAR = Path(__file__).parent / "java" / "tmpnav-enhsp.jar"
SERVER_CLASS = "tmpnav.EnhspServer"
#: seconds a stopped search has to end (the server's STOP_GRACE_MS)
STOP_GRACE = 2.0
#: seconds, beyond a solve's time limit and STOP_GRACE, before a server that has not answered
#: is given up for the run (a machine swapping, a JVM that hangs)
ANSWER_GRACE = 10.0
#: seconds between looks at whether a search was asked to stop (:func:`stop_all`)
POLL = 0.05
#: seconds the small search that warms a slot may take (:func:`warm`; it takes about 0.2 s)
WARM_TIMEOUT = 10.0


@dataclass(frozen=True)
class JvmRun:
    """What one ENHSP run in the JVM did: finished, or stopped at its time limit; the text
    of the Java exception it ended with, if any."""

    timed_out: bool
    error: str | None = None


@dataclass
class _Answer:
    """The server's answer to one request, once ``done`` is set."""

    done: threading.Event = field(default_factory=threading.Event)
    outcome: str = ""  # ok | error | timeout | stuck | ended (the server ended first)
    text: str = ""


class _Server:
    """The run's ENHSP server: its process, the answers it owes, and why it ended."""

    def __init__(self, java: str, options: str, jar: str):
        self.errors: IO[bytes] = tempfile.TemporaryFile()  # noqa: SIM115 (what the JVM says; kept while it runs)
        command = [java, *shlex.split(options), *FIXED_OPTIONS, "-cp", str(HELPER_JAR), SERVER_CLASS, jar]
        self.process = subprocess.Popen(
            command, stdin=subprocess.PIPE, stdout=subprocess.PIPE, stderr=self.errors, start_new_session=True
        )
        assert self.process.stdin is not None and self.process.stdout is not None
        self.pipes = (self.process.stdin.fileno(), self.process.stdout.fileno())
        self.lock = threading.Lock()
        self.answers: dict[str, _Answer] = {}
        self.ids = itertools.count()
        self.warmed = threading.Event()
        self.ended: str | None = None
        self.reader = threading.Thread(target=self._read, name="tmpnav-enhsp-answers", daemon=True)
        self.reader.start()

    def solve(self, args: list[str], timeout: float) -> tuple[str, _Answer]:
        """Ask for a search; its id and its answer-to-be."""
        key, answer = str(next(self.ids)), _Answer()
        with self.lock:
            if self.ended is not None:  # no answer is coming: say why now
                answer.outcome, answer.text = "ended", self.ended
                answer.done.set()
                return key, answer
            self.answers[key] = answer
        self._ask("solve", key, str(max(1, round(timeout * 1000))), *args)
        return key, answer

    def _ask(self, *fields: str) -> None:
        line = "\t".join(fields)
        if "\n" in line or any("\t" in f for f in fields[1:]):
            raise ValueError(f"an argument ENHSP's server cannot be given: {fields!r}")
        with self.lock:
            if self.ended is not None:
                return  # the answers were given when it ended
            try:
                assert self.process.stdin is not None
                self.process.stdin.write(line.encode() + b"\n")
                self.process.stdin.flush()
            except (BrokenPipeError, ValueError, OSError):
                pass  # it has ended: its reader says so to every pending answer

    def _read(self) -> None:
        assert self.process.stdout is not None
        for raw in self.process.stdout:
            fields = raw.decode(errors="replace").rstrip("\n").split("\t")
            if fields[0] == "warmed":
                self.warmed.set()
            elif fields[0] == "done":
                with self.lock:
                    answer = self.answers.pop(fields[1], None)
                if answer is not None:  # else a search that had already been given up
                    answer.outcome, answer.text = fields[2], fields[3] if len(fields) > 3 else ""
                    answer.done.set()
        self._end(f"the JVM ended: {self._said() or 'exit status ' + str(self.process.wait())}")
        with contextlib.suppress(OSError, ValueError):
            self.process.stdout.close()
            self.errors.close()

    def _said(self) -> str:
        with contextlib.suppress(OSError, ValueError):
            self.errors.seek(0)
            said = self.errors.read().decode(errors="replace")
            return " ".join(line.strip() for line in said.splitlines() if "JAVA_TOOL_OPTIONS" not in line)
        return ""

    def _end(self, why: str) -> None:
        with self.lock:
            if self.ended is None:
                self.ended = why
            pending, self.answers = list(self.answers.values()), {}
        for answer in pending:
            answer.outcome, answer.text = "ended", self.ended
            answer.done.set()
        self.warmed.set()

    def stop(self, key: str) -> None:
        self._ask("stop", key)

    def warm(self, slots: int, args: list[str]) -> None:
        """Ask for ``slots`` searches made ready, each with a search of ``args``; ``warmed``
        is set once they are."""
        self.warmed.clear()
        self._ask("warm", str(slots), str(round(WARM_TIMEOUT * 1000)), *args)

    def close(self) -> None:
        """End the server now, whatever it runs (a search's plan is in its file by the time
        the server answers; nothing else of the JVM's needs an orderly end)."""
        with self.lock:
            if self.ended is None:
                self.ended = "closed"
            with contextlib.suppress(OSError, ValueError):
                if self.process.stdin is not None:
                    self.process.stdin.close()
        with contextlib.suppress(OSError):
            self.process.kill()
        self.process.wait()
        self.reader.join(1.0)  # it has read the end of the output, and closes its files

    def forget(self) -> None:
        """In a process forked from this one (the oracle's workers): the server's pipes made
        /dev/null, so that the server sees its input close when tmpnav ends, not when the
        last worker does, and nothing a worker writes at its end reaches it."""
        nowhere = os.open(os.devnull, os.O_RDWR)
        for pipe in self.pipes:
            with contextlib.suppress(OSError):
                os.dup2(nowhere, pipe)
        os.close(nowhere)


class _Jvm:
    """The run's server, started on first use; ``broken`` says why it is not used."""

    def __init__(self) -> None:
        self.lock = threading.Lock()
        self.server: _Server | None = None
        self.broken: str | None = None
        self.warming: threading.Thread | None = None  # waiting for the slots' warm-up (:func:`warm`)
        self.closing = threading.Event()  # the run is ending: warm nothing more

    def ready(self, options: str) -> _Server | None:
        """The server (started now, with JVM ``options``, if it has not been), or None (and
        ``broken`` set) if it cannot run."""
        with self.lock:
            if self.server is None and self.broken is None:
                from tmpnav.java import find

                java = find()
                if java is None:
                    self.broken = "no Java 17+ to run it"
                    return None
                try:
                    self.server = _Server(str(java.executable), options, enhsp_jar())
                except (OSError, RuntimeError, ValueError) as err:
                    self.broken = f"the JVM did not start: {err}"
                    return None
                atexit.register(close)
            if self.server is not None and self.server.ended is not None and self.broken is None:
                self.broken = self.server.ended
            return self.server if self.broken is None else None

    def refuse(self, why: str) -> None:
        """Ask the server for no more searches in this run (those under way go on)."""
        with self.lock:
            self.broken = self.broken or why

    def give_up(self, why: str) -> None:
        """Stop using the server for the rest of the run, and end it."""
        self.refuse(why)
        if self.server is not None:
            self.server.close()


_JVM = _Jvm()


def _forked() -> None:
    if _JVM.server is not None:
        _JVM.server.forget()
    _JVM.server, _JVM.broken = None, "a process forked from the run's"


os.register_at_fork(after_in_child=_forked)
#: the runs in progress, each by the event that stops it (:func:`stop_all`)
_stops: set[threading.Event] = set()
_stops_lock = threading.Lock()


def stop_all() -> None:
    """Stop every search running in the JVM now (a signal is ending the run): each
    :func:`run` asks the server to stop its search and returns at once, as timed out."""
    with _stops_lock:
        for stop in _stops:
            stop.set()


def forced_process() -> bool:
    """Whether ``TMPNAV_ENHSP=process`` asks for a ``java`` process per solve."""
    return os.environ.get(MODE_ENV, "").strip().lower() == "process"


def unavailable() -> str | None:
    """Why ENHSP runs as a process per solve here (None: it runs in the run's JVM)."""
    if forced_process():
        return f"{MODE_ENV}=process"
    if _JVM.broken is not None:
        return _JVM.broken
    if not HELPER_JAR.is_file():
        return f"{HELPER_JAR} is missing (make java builds it)"
    return None


def usable(options: str) -> bool:
    """Whether this solve can run in the run's JVM (starting its server now, with the JVM
    options ``options``, if need be: a process start, not waited for)."""
    return unavailable() is None and _JVM.ready(options) is not None


def describe() -> str:
    """For ``tmpnav doctor``'s Java line: how ENHSP runs, and why."""
    reason = unavailable()
    if reason is None:
        return "in one JVM for the run, a server process beside tmpnav"
    return f"in a JVM process per solve ({reason})"


def enhsp_jar() -> str:
    """The path of up_enhsp's enhsp.jar (its ``ENHSP_JAR``), found without importing up_enhsp."""
    spec = importlib.util.find_spec("up_enhsp")
    if spec is None or not spec.submodule_search_locations:
        raise RuntimeError("up_enhsp is not installed")
    return os.path.join(next(iter(spec.submodule_search_locations)), "ENHSP", "enhsp.jar")


def run(args: list[str], timeout: float) -> JvmRun:
    """Run ENHSP's ``main`` with ``args`` (up_enhsp's, without ``java -jar``) in the run's
    JVM, stopped after ``timeout`` seconds. Call :func:`usable` first."""
    server = _JVM.server
    if server is None:
        return JvmRun(False, "ENHSP's server was not started")
    key, answer = server.solve(args, timeout)
    ended = _wait(answer.done, timeout + STOP_GRACE + ANSWER_GRACE)
    if ended == "stopped":  # the run is ending: asked to stop, not waited for (see stop_all)
        server.stop(key)
        return JvmRun(True)
    if ended == "limit":
        _JVM.give_up(f"ENHSP's server did not answer within {timeout + STOP_GRACE + ANSWER_GRACE:.0f} s")
        return JvmRun(True)
    if answer.outcome == "ok":
        return JvmRun(False)
    if answer.outcome == "timeout":
        return JvmRun(True)
    if answer.outcome == "stuck":
        _JVM.refuse("a search could not be stopped at its time limit (Java 20+ has no Thread.stop)")
        return JvmRun(True)
    if answer.outcome == "ended":
        _JVM.refuse(answer.text)
    return JvmRun(False, answer.text or answer.outcome)


def warm(slots: int, sample: Callable[[], contextlib.AbstractContextManager[list[str]]]) -> None:
    """Have ``slots`` searches made ready while the caller goes on: ENHSP's classes loaded in
    a slot of its own for each, and one search of a small problem run in each (``sample``: a
    context giving ENHSP's arguments for it, its files kept while inside), so that the run's
    first searches do not pay for either. Measured on the 10-room corridor's 24 sub-problems,
    one after another in a fresh JVM: the first took 0.79 s (JVM start 0.25 s, a slot 0.32 s,
    its first search 0.2 s against 0.04 s warm), and all took 2.07 s cold against 1.11 s warm.
    The server makes the slots one after another; a search that finds no idle slot meanwhile
    waits for the next. A daemon thread keeps the sample's files until the server is done."""
    server = _JVM.server
    if server is None or _JVM.closing.is_set() or (_JVM.warming is not None and _JVM.warming.is_alive()):
        return

    def ready() -> None:
        with contextlib.suppress(Exception), sample() as args:  # the sample's files: the searches go on
            server.warm(slots, args)
            while not server.warmed.wait(POLL) and not _JVM.closing.is_set():
                pass

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


def close() -> None:
    """End the run's server, its searches with it (at Python's exit; the command line's end)."""
    _JVM.closing.set()
    stop_all()
    server = _JVM.server
    if server is not None:
        server.close()


def release() -> bool:
    """End the run's server once its searches are over, and say whether there was one: a
    command that goes on to write figures or execute sessions does not keep the JVM's heap
    (300 MB at 100 rooms and 16 robots). A later search starts a new server; a server the run
    stopped using (``broken``) stays stopped. Not while searches are under way or being made
    ready (:func:`warm`): then nothing is ended."""
    warming = _JVM.warming
    if warming is not None and warming.is_alive():
        return False
    with _stops_lock:
        if _stops:
            return False
    with _JVM.lock:
        server = _JVM.server
        if server is None or _JVM.broken is not None:
            return False
        _JVM.server = None
    server.close()
    return True


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
