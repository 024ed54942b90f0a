"""``tmpnav simulate``'s sessions: the schedule executed many times, with and without mutual observations.

Config 1 uses mutual observations, config 2 ignores them; both run on the same draws, session
by session, so the comparison is paired (paper, Fig. 3(a)). What a session records:

* the position error (distance between the true and the estimated position) when a robot
  reaches each node of its paths; the worst-case error of a robot is the largest of its
  average errors over the nodes, as in the paper;
* when it reached each node, and its moves as executed (:class:`~tmpnav.results.Schedule`):
  the executed makespan, and how long each robot waited for its partners or for planned starts;
* the control steps after which a robot's true pose hit a wall, or touched another robot's:
  the rates of executions with any (:class:`Rate`, with a 95% Clopper-Pearson interval), which
  the collision bound of docs/models.md keeps at most delta.
"""

from __future__ import annotations

import math
import multiprocessing
import os
import signal
import time
from collections.abc import Callable
from concurrent.futures import ProcessPoolExecutor
from dataclasses import dataclass, field
from multiprocessing.connection import Connection

import numpy as np

from tmpnav.belief.intervals import clopper_pearson
from tmpnav.errors import TmpnavError
from tmpnav.execution.consistency import Nees
from tmpnav.execution.consistency import gather as gather_consistency
from tmpnav.execution.localisers import Localisation
from tmpnav.execution.moves import QueuedMove, queues
from tmpnav.execution.recovery import BEHAVIOURS
from tmpnav.execution.schedule import STEP_BUDGET
from tmpnav.execution.session import Session
from tmpnav.execution.trace import Draws, HitEvent, SessionTrace
from tmpnav.lifetime import gather, signals_held
from tmpnav.oracle.executors import die_with_parent
from tmpnav.results import PlanReport, Schedule
from tmpnav.types import Scenario
from tmpnav.world import World
from tmpnav.world.visibility import LandmarkVisibility

CONFIGS = {1: True, 2: False}  # config -> with mutual observations


@dataclass(frozen=True)
class Rate:
    """Executions (sessions) in which something happened at least once, out of all of them."""

    events: int
    sessions: int

    @property
    def value(self) -> float:
        return self.events / self.sessions if self.sessions else 0.0

    @property
    def interval(self) -> tuple[float, float]:
        """The exact 95% confidence interval of the rate (Clopper-Pearson)."""
        return clopper_pearson(self.events, self.sessions)

    def text(self) -> str:
        lo, hi = self.interval
        return f"{self.events}/{self.sessions} = {100 * self.value:.1f}% (95% CI {100 * lo:.1f}-{100 * hi:.1f}%)"


@dataclass
class ExecutionResult:
    """Every session's position errors, node times and executed schedule, in both configurations."""

    robots: list[str]
    nodes: dict[str, list[int]]  # robot -> roadmap node at each recorded point (start first)
    errors: dict[tuple[int, str], np.ndarray]  # (config, robot) -> (sessions, points) m
    truncated_sessions: int
    times: dict[tuple[int, str], np.ndarray]  # (config, robot) -> (sessions, points) s, when reached
    planned_times: dict[str, list[float | None]]  # robot -> planned arrival at each point (s)
    schedules: dict[int, list[Schedule]]  # config -> each session's moves as executed
    planned: Schedule  # the plan's schedule
    wall_hits: dict[tuple[int, str], np.ndarray]  # (config, robot) -> (sessions,) control steps hitting a wall
    contacts: dict[tuple[int, str], np.ndarray]  # (config, robot) -> (sessions,) control steps touching a robot
    planned_nees: dict[tuple[int, str], np.ndarray]  # (config, robot) -> (sessions, points): NEES vs the plan
    filter_nees: dict[tuple[int, str], np.ndarray]  # (config, robot) -> the filter's own NEES at every step
    beams: dict[tuple[int, str], tuple[int, int]]  # (config, robot) -> range beams used, rejected by the gate
    #: (config, robot, plan step) -> (sessions,) control steps hitting a wall / touching a robot during the
    #: move (or standing after it; step -1: before the robot's first move)
    move_hits: dict[tuple[int, str, int], np.ndarray]
    move_contacts: dict[tuple[int, str, int], np.ndarray]
    bounds: dict[tuple[str, int], float]  # (robot, plan step) -> the move's collision bound as planned
    #: (robot, plan step) -> every driving step's actual error, localiser's and plan's covariance, of
    #: config 1 (tmpnav.execution.consistency)
    consistency: dict[tuple[str, int], np.ndarray] = field(default_factory=dict)
    #: the executing localiser, the site and the true motion noise, in words
    localiser: str = ""
    #: the configurations run: both (1 with mutual observations, 2 without) with the EKF; 1 only with
    #: AMCL, which localises each robot on its own
    configs: tuple[int, ...] = (1, 2)
    #: nav2's recovery behaviours run in config 1, by name, summed over the sessions
    #: (tmpnav.execution.recovery), and each session's moves nav2 gave up
    recoveries: dict[str, int] = field(default_factory=dict)
    given_up: np.ndarray = field(default_factory=lambda: np.zeros(0, dtype=int))
    #: config -> every contact's first step (session, 0-based, and the event), in session order
    hit_events: dict[int, list[tuple[int, HitEvent]]] = field(default_factory=dict)

    def mean_errors(self, config: int, robot: str) -> np.ndarray:
        """(points,) m: the robot's position error at each point of its paths, averaged over the sessions."""
        return np.nanmean(self.errors[(config, robot)], axis=0)

    def worst(self, config: int, robot: str) -> float:
        """The worst-case position error: the largest average error over the path nodes."""
        return float(np.nanmax(self.mean_errors(config, robot)))

    def reduction(self, robot: str) -> float:
        """How much lower (%) the worst-case error is with mutual observations."""
        w1, w2 = self.worst(1, robot), self.worst(2, robot)
        return 100.0 * (w2 - w1) / w2 if w2 > 0 else 0.0

    @property
    def starved(self) -> str:
        """The robot that suffers most without mutual observations (the paper's r')."""
        return max(self.robots, key=lambda r: self.worst(2, r))

    def makespans(self, config: int) -> np.ndarray:
        """(sessions,) s: when each session's last move ended."""
        return np.array([s.makespan for s in self.schedules[config]], dtype=float)

    def waits(self, config: int, robot: str) -> np.ndarray:
        """(sessions,) s: how long the robot waited before its moves (for a partner or a planned start)."""
        return np.array([s.waits(robot) for s in self.schedules[config]], dtype=float)

    def wall_rate(self, config: int, robot: str | None = None) -> Rate:
        """Executions in which the robot's (any robot's, for None) true pose hit a wall."""
        return self._rate(self.wall_hits, config, robot)

    def contact_rate(self, config: int, robot: str | None = None) -> Rate:
        """Executions in which the robot (any pair of robots, for None) touched another."""
        return self._rate(self.contacts, config, robot)

    def nees(self, config: int, robot: str | None = None) -> Nees:
        """The position NEES against the planned covariance at the path points the robot (every
        robot, for None) reached (:class:`~tmpnav.execution.consistency.Nees`: its median, 1.39
        when the errors agree with the plan, and its share beyond 3 sigma)."""
        robots = self.robots if robot is None else [robot]
        return Nees.of(np.concatenate([self.planned_nees[(config, r)].ravel() for r in robots]))

    def own_nees(self, config: int, robot: str | None = None) -> Nees:
        """The position NEES against the executing filter's own covariance over every control step."""
        robots = self.robots if robot is None else [robot]
        return Nees.of(np.concatenate([self.filter_nees[(config, r)] for r in robots]))

    def move_rates(self, config: int) -> list[tuple[str, int, Rate, Rate, float]]:
        """Per move (robot, plan step): the executions with a wall hit and with a contact during it,
        and its collision bound as planned, in plan order."""
        sessions = len(self.schedules[config])
        zero = np.zeros(sessions, dtype=int)
        out = []
        for (robot, step), bound in sorted(self.bounds.items(), key=lambda x: (x[0][1], x[0][0])):
            hits = self.move_hits.get((config, robot, step), zero)
            touches = self.move_contacts.get((config, robot, step), zero)
            out.append(
                (robot, step, Rate(int((hits > 0).sum()), sessions), Rate(int((touches > 0).sum()), sessions), bound)
            )
        return out

    def _rate(self, counts: dict[tuple[int, str], np.ndarray], config: int, robot: str | None) -> Rate:
        robots = self.robots if robot is None else [robot]
        any_event = np.any([counts[(config, r)] > 0 for r in robots], axis=0)
        return Rate(int(np.sum(any_event)), len(self.schedules[config]))


def recorded_nodes(moves: dict[str, tuple[QueuedMove, ...]], starts: dict[str, int]) -> dict[str, list[int]]:
    """Robot -> the roadmap node of each point a session records: its start, then its paths' nodes."""
    return {r: [starts[r], *(n for m in queue for n in m.nodes[1:])] for r, queue in moves.items()}


@dataclass(frozen=True, eq=False)
class _Sessions:
    """What every session of one execution shares (sent once to each worker process)."""

    scenario: Scenario
    world: World
    moves: dict[str, tuple[QueuedMove, ...]]
    vis: LandmarkVisibility
    seed: int
    steps: int  # control steps drawn per session
    beams: int
    localisation: Localisation

    @property
    def configs(self) -> dict[int, bool]:
        """Config -> with mutual observations: both with the EKF, the first alone with AMCL."""
        return {1: True} if self.localisation.particle_filter else CONFIGS

    def run(self, s: int) -> tuple[dict[int, SessionTrace], bool]:
        """Session ``s`` in both configurations (the same draws), and whether it was cut short.
        With AMCL in a process of its own, forked from this one: the bindings draw each filter's
        initial particles from a counter of the process (docs/amcl.md, "Seeding"), so a session
        run after others in the same process would draw other particles, and the results would
        depend on how the sessions were spread over the workers."""
        if self.localisation.particle_filter and "fork" in multiprocessing.get_all_start_methods():
            return _forked(self._run, s)
        return self._run(s)

    def _run(self, s: int) -> tuple[dict[int, SessionTrace], bool]:
        scenario, world = self.scenario, self.world
        robots = len(scenario.robots)
        draws = Draws.draw(self.seed, s, robots, self.steps, world.landmark_xy.shape[0], self.beams)
        traces = {
            c: Session(scenario, world, self.moves, draws, self.vis, mutual, self.localisation, s).run()
            for c, mutual in self.configs.items()
        }
        return traces, any(t.truncated for t in traces.values())


def _forked(run: Callable[[int], tuple[dict[int, SessionTrace], bool]], s: int) -> tuple[dict[int, SessionTrace], bool]:
    """``run(s)`` in a child process forked for it (it ends with this one), its result sent back."""
    mp = multiprocessing.get_context("fork")
    reader, writer = mp.Pipe(duplex=False)
    child = mp.Process(target=_child, args=(run, s, writer, os.getpid()), daemon=False)
    child.start()
    writer.close()
    try:
        ok, value = reader.recv()
    except EOFError:
        child.join()
        code = child.exitcode
        raise TmpnavError(f"simulated session {s} ended without a result (its process exited {code})") from None
    finally:
        child.join()
    if not ok:
        raise value
    return value


def _child(run: Callable[[int], object], s: int, writer: Connection, parent: int) -> None:
    die_with_parent(parent)
    try:
        writer.send((True, run(s)))
    except BaseException as e:  # the parent raises it
        writer.send((False, e))
    finally:
        writer.close()


_SHARED: _Sessions | None = None


def _init_worker(shared: _Sessions, parent: int) -> None:
    global _SHARED
    signal.signal(signal.SIGTERM, signal.SIG_DFL)  # a worker just ends; Ctrl-C is the parent's business
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    # held while the parent forked (tmpnav.lifetime.signals_held), and a fork keeps the mask: a
    # worker that blocked SIGTERM outlived the pool stopped at the time limit, and the command,
    # its files written, waited for it at exit forever
    signal.pthread_sigmask(signal.SIG_UNBLOCK, {signal.SIGTERM})
    die_with_parent(parent)
    _SHARED = shared


def _run_session(s: int) -> tuple[dict[int, SessionTrace], bool]:
    assert _SHARED is not None
    return _SHARED.run(s)


def execute(
    report: PlanReport,
    sessions: int = 25,
    seed: int = 0,
    workers: int | None = None,
    localisation: Localisation | None = None,
    seconds: float | None = None,
) -> ExecutionResult:
    """Execute ``report``'s schedule ``sessions`` times in both configurations, on ``workers``
    local processes (one per core when None; the same results, session by session, as in one),
    localised as ``localisation`` says (tmpnav's EKF by default). With ``seconds`` (what the run's
    time limit leaves), the sessions done when that time is up, in order, at least the first."""
    localisation = (localisation or Localisation()).following(report.scenario.models.driving)
    scenario, world = report.scenario, report.world
    robots = [r.name for r in scenario.robots]
    moves = queues(report)
    # the draws' length: as many steps as the plan's trajectories hold together, times the
    # budget (sessions drawn before the team moved at once draw the same numbers)
    planned = sum(len(t) for t in report.trajectories.values())
    sensor = scenario.models.range_sensor
    shared = _Sessions(
        scenario,
        world,
        moves,
        LandmarkVisibility(world, scenario.models.landmark_sensor.range),
        seed,
        STEP_BUDGET * planned + 100,
        sensor.beams if sensor is not None else 0,
        localisation,
    )
    if sensor is not None:
        _ = world.signed_distance  # once, before the workers fork
    workers = min(workers or os.cpu_count() or 1, sessions)
    until = math.inf if seconds is None else time.perf_counter() + seconds
    if workers <= 1 or "fork" not in multiprocessing.get_all_start_methods():
        done: list[tuple[dict[int, SessionTrace], bool]] = []
        for s in range(sessions):
            if done and time.perf_counter() >= until:
                break
            done.append(shared.run(s))
    else:
        done = _in_workers(shared, sessions, workers, until)
    traces: dict[int, list[SessionTrace]] = {c: [t[c] for t, _ in done] for c in shared.configs}
    truncated = sum(cut for _, cut in done)
    result = _result(report, robots, moves, traces, truncated)
    result.localiser = localisation.describe(scenario.models.motion_noise)
    return result


def _in_workers(
    shared: _Sessions, sessions: int, workers: int, until: float = math.inf
) -> list[tuple[dict[int, SessionTrace], bool]]:
    """The sessions on local worker processes (forked: they end with this process, however it
    ends), in order; those done by ``until`` (``time.perf_counter``), at least the first."""
    mp = multiprocessing.get_context("fork")
    pool = ProcessPoolExecutor(workers, mp_context=mp, initializer=_init_worker, initargs=(shared, os.getpid()))
    try:
        with signals_held():  # the first submissions fork the workers
            futures = [pool.submit(_run_session, s) for s in range(sessions)]
        done: list[tuple[dict[int, SessionTrace], bool]] = []
        for trace in gather(futures):
            done.append(trace)
            if time.perf_counter() >= until and len(done) < sessions:  # the time limit: the rest stopped
                _stop(pool)
                break
        return done
    except BaseException:
        _stop(pool)
        raise
    finally:
        pool.shutdown(wait=True)


def _stop(pool: ProcessPoolExecutor) -> None:
    """The pool's workers stopped now, the sessions not started cancelled."""
    for process in list(getattr(pool, "_processes", {}).values()):
        process.terminate()
    pool.shutdown(wait=False, cancel_futures=True)


def _result(
    report: PlanReport,
    robots: list[str],
    moves: dict[str, tuple[QueuedMove, ...]],
    traces: dict[int, list[SessionTrace]],
    truncated: int,
) -> ExecutionResult:
    names = tuple(robots)
    configs = tuple(traces)
    return ExecutionResult(
        robots=robots,
        nodes=recorded_nodes(moves, report.roadmap.starts),
        errors={(c, r): np.array([t.errors[r] for t in traces[c]], dtype=float) for c in configs for r in robots},
        truncated_sessions=truncated,
        times={(c, r): np.array([t.times[r] for t in traces[c]], dtype=float) for c in configs for r in robots},
        planned_times={r: [0.0, *(t for m in moves[r] for t in m.arrivals)] for r in robots},
        schedules={c: [t.schedule(names) for t in traces[c]] for c in configs},
        planned=report.schedule,
        wall_hits={(c, r): np.array([t.wall_hits[r] for t in traces[c]], dtype=int) for c in configs for r in robots},
        contacts={(c, r): np.array([t.contacts[r] for t in traces[c]], dtype=int) for c in configs for r in robots},
        planned_nees={
            (c, r): np.array([t.planned_nees[r] for t in traces[c]], dtype=float) for c in configs for r in robots
        },
        filter_nees={
            (c, r): np.array([v for t in traces[c] for v in t.own_nees[r]], dtype=float)
            for c in configs
            for r in robots
        },
        beams={
            (c, r): (sum(t.beams[r][0] for t in traces[c]), sum(t.beams[r][1] for t in traces[c]))
            for c in configs
            for r in robots
        },
        move_hits=_per_move(traces, "move_hits"),
        move_contacts=_per_move(traces, "move_contacts"),
        bounds={
            (robot, action.index - 1): float(bound)
            for action in report.actions
            for (robot, _, _), bound in zip(action.moves, action.risk, strict=False)
        },
        consistency=gather_consistency([t.consistency for t in traces[configs[0]]]),
        configs=configs,
        recoveries={name: sum(t.recoveries.get(name, 0) for t in traces[configs[0]]) for name in BEHAVIOURS},
        given_up=np.array([len(t.given_up) for t in traces[configs[0]]], dtype=int),
        hit_events={c: [(s, e) for s, t in enumerate(traces[c]) for e in t.hit_events] for c in configs},
    )


def _per_move(traces: dict[int, list[SessionTrace]], what: str) -> dict[tuple[int, str, int], np.ndarray]:
    """(config, robot, step) -> each session's count of ``what`` (SessionTrace.move_hits or .move_contacts)."""
    out: dict[tuple[int, str, int], np.ndarray] = {}
    for c, ts in traces.items():
        for s, t in enumerate(ts):
            for (robot, step), n in getattr(t, what).items():
                out.setdefault((c, robot, step), np.zeros(len(ts), dtype=int))[s] = n
    return out
