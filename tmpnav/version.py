"""tmpnav's version (a module of its own: every layer may read it, and ``import tmpnav`` is the API)."""

__version__ = "0.1.0"
