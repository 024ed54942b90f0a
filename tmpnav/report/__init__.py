"""Stage 8: the report of a plan (plan.json, the terminal summary) and every figure.

Only this package imports matplotlib, and only in its modules: importing the package
itself is cheap, so the command line can check an output's suffix before any work.
"""

#: picture formats by file suffix (matplotlib's, without those needing LaTeX or
#: giving headerless pixels); a figure is written in the format its suffix names
FIGURE_FORMATS = ("png", "svg", "svgz", "pdf", "eps", "ps", "jpg", "jpeg", "tif", "tiff", "webp", "gif")


def figure_format(name: str) -> str | None:
    """The picture format a file name's suffix names (``plan.SVG`` -> ``svg``), or None."""
    suffix = name.rpartition(".")[2].lower() if "." in name else ""
    return suffix if suffix in FIGURE_FORMATS else None


def figure_suffixes() -> str:
    """The accepted suffixes, for messages: ``.png, .svg, ...``."""
    return ", ".join(f".{f}" for f in FIGURE_FORMATS)
