"""Stage 1: a scenario YAML file -> a validated :class:`~tmpnav.types.Scenario`."""

from tmpnav.scenario.load import display_path, load, load_partial

__all__ = ["display_path", "load", "load_partial"]
