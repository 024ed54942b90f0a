"""The semantic attachment: action costs for the task-level search, from the oracle.

The paper's task planner calls an external module whenever it expands an action; that
module plans the motion and returns its cost. Here the task search (:mod:`tmpnav.task`)
asks a cost model (:class:`tmpnav.task.model.CostModel`) and the models of this package
answer through the oracle (:mod:`tmpnav.oracle`): :mod:`~tmpnav.attachment.canonical` with
every move starting from a canonical state (the cost table's semantics), and
:mod:`~tmpnav.attachment.carried` from the beliefs the robots carry at that point of the
plan. This package joins stage 5 (oracle) and stage 6 (task) and is wired in by
:mod:`tmpnav.pipeline`; neither stage imports it.
"""
