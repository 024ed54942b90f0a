"""Which std tracks AMCL's actual error from move to move: AMCL's own, or the plan's?

    .venv/bin/python benchmarks/bench_std_tracks.py CONSISTENCY.csv [...]

Each consistency.csv (``tmpnav simulate --localiser amcl -o DIR``) has, per robot and move, the
RMS of AMCL's actual position error over the move's driving steps, AMCL's own std (its particle
cloud's covariance) and the plan's predicted std. Over the moves of each file: the correlation
of the actual error with each std, and the ratio of each std to the error (median and spread
over the moves). A model whose std rises and falls with the error where it rises and falls
(long walls, open floor) has the higher correlation; a scale alone cannot raise it.
"""

from __future__ import annotations

import argparse
import csv
from pathlib import Path

import numpy as np


def tracks(path: Path) -> str:
    """One line: the file, its moves, and for AMCL's own std and the plan's: corr and ratios."""
    rows = [r for r in csv.DictReader(path.open()) if int(r["driving_steps"]) > 0]
    error = np.array([float(r["rms_error_m"]) for r in rows])
    cols = {"AMCL's own std": "localiser_std_m", "plan's std": "planned_std_m"}
    parts = []
    for name, col in cols.items():
        std = np.array([float(r[col]) for r in rows])
        ratio = std / error
        q = np.percentile(ratio, [10, 50, 90])
        parts.append(
            f"{name}: corr {np.corrcoef(error, std)[0, 1]:.2f}, std / error {q[1]:.2f} (p10-p90 {q[0]:.2f}-{q[2]:.2f})"
        )
    return f"{path.name}: {len(rows)} moves; " + "; ".join(parts)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("files", nargs="+", type=Path)
    for path in parser.parse_args().files:
        print(tracks(path))


if __name__ == "__main__":
    main()
