"""figures.render: the picture savefig(bbox_inches="tight") gives, laid out once."""

from __future__ import annotations

import io
from typing import Any

import numpy as np
import pytest
from matplotlib.figure import Figure
from PIL import Image

from tmpnav.report import figures as fg
from tmpnav.report.plan_plot import plan_figure
from tmpnav.report.schedule_plot import schedule_figure


def pixels(draw: Any) -> np.ndarray:
    """The RGBA pixels of what ``draw(buffer)`` writes."""
    buffer = io.BytesIO()
    draw(buffer)
    with Image.open(io.BytesIO(buffer.getvalue())) as image:
        return np.asarray(image.convert("RGBA"))


def tight(fig: Figure) -> Any:
    return lambda out: fig.savefig(out, dpi=110, bbox_inches="tight", format="png")


def sticking_out() -> Figure:
    """A figure whose title, tick labels and legend reach beyond the figure on every side."""
    fig, ax = fg.subplots((4.0, 3.0))
    fig.subplots_adjust(left=0.0, right=0.8, bottom=0.0, top=1.0)
    ax.plot([0, 1], [0, 1], label="a line with a long label")
    ax.set_title("a title\non two lines")
    ax.set_ylabel("y [m]")
    ax.legend(loc="upper left", bbox_to_anchor=(1.0, 1.0))
    return fig


def test_the_same_pixels_as_savefig_tight_with_artists_outside_the_figure() -> None:
    expected = pixels(tight(sticking_out()))
    drawn = pixels(lambda out: fg.render(sticking_out(), out))
    assert drawn.shape == expected.shape and drawn.shape[1] > 4 * 110  # wider than the figure: the legend
    assert np.array_equal(drawn, expected)


def test_vector_formats_keep_matplotlibs_tight_box() -> None:
    """An SVG's text is measured by the SVG renderer, not Agg's: matplotlib's own "tight"."""
    assert fg.tight_box(sticking_out(), 110, "svg") == "tight"
    assert fg.tight_box(sticking_out(), 110, "png") != "tight"


@pytest.mark.slow
@pytest.mark.parametrize("figure", [plan_figure, schedule_figure])
def test_plan_and_schedule_the_same_pixels_as_savefig_tight(plan_report: Any, figure: Any) -> None:
    expected = pixels(tight(figure(plan_report)))
    assert np.array_equal(pixels(lambda out: fg.render(figure(plan_report), out)), expected)
