"""Figures of ``tmpnav bench`` and ``tmpnav simulate`` (paper, Fig. 3 (a), (b), (c))."""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np
from matplotlib.figure import Figure

from tmpnav.report import figures as fg

if TYPE_CHECKING:
    from tmpnav.bench.table import Medians
    from tmpnav.execution import ExecutionResult

ENCODING_COLORS = {"mixed": "#1f77b4", "paper": "#d62728", "single": "#2ca02c"}


def bench_figure(medians: Medians, axis: str, title: str, timeout: float | None = None) -> Figure:
    """Median total planning time (with the quartiles) per encoding and cache phase.

    Log scale on both experiments: the warm runs (a cache lookup), the default encoding and
    the paper's encoding differ by orders of magnitude. A point where every cold run timed
    out is drawn as an open marker at the time limit: the time is at least that."""
    fig, ax = fg.subplots((7.5, 4.8))
    encodings = sorted({k[0] for k in medians})
    for enc in encodings:
        color = ENCODING_COLORS.get(enc, "#7f7f7f")
        for phase, style in (("cold", "-"), ("replan", "--"), ("warm", ":")):
            pts = sorted(p for e, ph, p in medians if e == enc and ph == phase and medians[(e, ph, p)].total)
            if not pts:
                continue
            y = np.array([medians[(enc, phase, p)].total for p in pts], dtype=float)
            lo = np.array([medians[(enc, phase, p)].q1 for p in pts], dtype=float)
            hi = np.array([medians[(enc, phase, p)].q3 for p in pts], dtype=float)
            label = {"cold": "cold cache", "warm": "warm cache", "replan": "warm costs, planner re-run"}[phase]
            ax.plot(pts, y, style, marker="o", color=color, label=f"{enc}, {label}")
            ax.fill_between(pts, lo, hi, color=color, alpha=0.12 if phase == "cold" else 0.06)
        timeouts = sorted(p for e, ph, p in medians if e == enc and ph == "cold" and medians[(e, ph, p)].solved == 0)
        if timeouts and timeout:
            ax.plot(
                timeouts,
                [timeout] * len(timeouts),
                "^",
                mfc="none",
                ms=9,
                color=color,
                label=f"{enc}, cold: no run within the {timeout:g} s limit",
            )
    ax.set_xticks(sorted({k[2] for k in medians}))
    ax.set_xlabel("rooms to visit" if axis == "rooms" else "robots")
    ax.set_ylabel("planning time [s] (median, quartiles)")
    ax.set_yscale("log")
    if axis == "rooms":
        ax.axhline(5.0, color="black", lw=0.7, ls=":", label="paper: 5 s at 10 rooms")
    ax.grid(alpha=0.3)
    ax.set_title(title, fontsize=10)
    ax.legend(fontsize=8)
    return fig


def errors_figure(result: ExecutionResult, title: str) -> Figure:
    """Average position error at each node of each robot's trajectory, both configurations."""
    fig, ax = fg.subplots((7.5, 4.8))
    for index, robot in enumerate(result.robots):
        color = fg.robot_color(index)
        for config, style in ((1, "-"), (2, "--")):
            if config not in result.configs:
                continue
            err = result.mean_errors(config, robot)
            label = f"{robot}, {'with' if config == 1 else 'without'} mutual observations (config {config})"
            if result.configs == (1,):
                label = f"{robot}, localised by AMCL"
            ax.plot(np.arange(len(err)), err, style, marker="o", ms=3, color=color, label=label)
    ax.set_xlabel("node along the robot's planned trajectory")
    ax.set_ylabel("average position error [m]")
    ax.grid(alpha=0.3)
    ax.set_title(title, fontsize=10)
    ax.legend(fontsize=8)
    return fig
