"""Plan execution (``tmpnav simulate``): the plan's schedule run many times with simulated noise
(paper, Fig. 3(a)), every robot moving at once.

Each session draws the robots' true initial poses from their initial beliefs, then the whole
team executes the schedule on one clock (:mod:`.session`): every robot follows its own queue
of moves (:mod:`.moves`) with a waypoint follower steering on its own estimate
(:mod:`.control`), a paired move starts when both robots are ready, and no move starts before
its planned start (:mod:`.schedule`). Observations are generated from the true poses (landmarks in range, field
of view and line of sight; any two robots in range and line of sight) with sensor noise, and
the team's joint EKF estimates the poses (:mod:`.fast_ekf`, compiled, held to the filterpy
reference :mod:`.joint_ekf`), or with ``--localiser amcl`` every robot's AMCL (:mod:`.amcl_team`).

Config 1 uses mutual observations, config 2 ignores them, on the same random draws
(:mod:`.result`). Every session counts the true poses that hit a wall and the robots that
touch, which the collision bound (:mod:`tmpnav.belief.risk`) bounds; :mod:`.text` writes the
summary and the CSV files.
"""

from tmpnav.execution.control import ALIGN, ARRIVED, control, reached
from tmpnav.execution.moves import QueuedMove, queues
from tmpnav.execution.result import ExecutionResult, Rate, execute
from tmpnav.execution.schedule import STEP_BUDGET
from tmpnav.execution.session import Session
from tmpnav.execution.text import error_summary, errors_csv, hits_csv, moves_csv, sessions_csv
from tmpnav.execution.trace import Draws, SessionTrace

__all__ = [
    "ALIGN",
    "ARRIVED",
    "STEP_BUDGET",
    "Draws",
    "ExecutionResult",
    "QueuedMove",
    "Rate",
    "Session",
    "SessionTrace",
    "control",
    "error_summary",
    "errors_csv",
    "execute",
    "hits_csv",
    "moves_csv",
    "queues",
    "reached",
    "sessions_csv",
]
