"""tmpnav: multi-robot task-motion planning for navigation in belief space.

The pipeline (one subpackage per stage, joined in :mod:`tmpnav.pipeline`)::

    scenario (YAML) -> world -> roadmap (OMPL PRM) -> belief (EKF models)
      -> oracle (+ disk cache) -> task (PDDL via unified-planning, ENHSP) -> report
"""

from tmpnav.version import __version__

#: the Python API (tmpnav.api), imported on first use so that `import tmpnav` stays fast
_API = ("PlanResult", "Step", "export_nav2", "load", "plan", "segment_map", "write_skeleton")
__all__ = ["__version__", *_API]


def __getattr__(name: str) -> object:
    if name in _API:
        from tmpnav import api

        return getattr(api, name)
    raise AttributeError(f"module 'tmpnav' has no attribute {name!r}")
