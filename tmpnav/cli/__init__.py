"""The ``tmpnav`` command line: the only place that prints and chooses exit codes.

``commands`` defines the click group and its commands (``rooms`` and ``evaluation`` add
``tmpnav rooms``, ``tmpnav simulate`` and ``tmpnav bench`` to it, ``tool`` the commands about
tmpnav itself: cache, configs, doctor, reference), ``options`` what they share
(error handling, the scenario argument, output and oracle options). Library code raises typed
exceptions (tmpnav.errors); only this package turns them into messages and exit codes.
"""

from tmpnav.cli import evaluation as _evaluation  # noqa: F401  (registers `tmpnav simulate`, `tmpnav bench`)
from tmpnav.cli import replan as _replan  # noqa: F401  (registers `tmpnav replan`)
from tmpnav.cli import rooms as _rooms  # noqa: F401  (registers `tmpnav rooms`)
from tmpnav.cli import serve as _serve  # noqa: F401  (registers `tmpnav serve`)
from tmpnav.cli import tool as _tool  # noqa: F401  (registers `tmpnav cache`, `configs`, `doctor`, `reference`)
from tmpnav.cli.commands import cli, main
from tmpnav.cli.options import writing

__all__ = ["cli", "main", "writing"]
