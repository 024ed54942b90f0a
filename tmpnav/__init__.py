"""tmpnav: multi-robot task-motion planning for navigation in belief space.

The pipeline (one subpackage per stage, joined in :mod:`tmpnav.pipeline`)::

    scenario (YAML) -> world -> roadmap (OMPL PRM) -> belief (EKF models)
      -> oracle (+ disk cache) -> task (PDDL via unified-planning, ENHSP) -> report
"""

__version__ = "0.1.0"
