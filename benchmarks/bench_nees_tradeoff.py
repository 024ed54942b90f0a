"""Issue 55's two consistency targets against each other: how far one scale of the plan's covariance
can meet both.

The targets ask of the plan's predicted covariance P against nav2's AMCL's actual error e over the
driving steps: a median NEES eᵀ P⁻¹ e between 1 and 4, and at most 5% of steps beyond 3 sigma
(NEES > 9). A model that predicted k times the std (k² P) would give each step the NEES / k². So
one execution run gives the whole trade-off: for each k the median NEES and the share beyond 3
sigma, and the range of k (if any) that meets both. AMCL's errors have long tails (kidnaps along
corridors, recoveries), which is what makes the two pull apart.

Each scenario (the shipped and generated ones of bench_amcl_scenarios, with the AMCL model that
is the default) is planned with --accept-risk and executed ``--sessions`` times with nav2's AMCL
on the typical site. Results: ``amcl/tradeoff/NAME.csv`` (k, median NEES, share beyond 3 sigma)
and the table printed at the end (benchmarks/README.md, "The two consistency targets").

    .venv/bin/python benchmarks/bench_nees_tradeoff.py [--sessions 4] [--only NAME ...]
        [--prediction-noise] [--information F] [--heading-blur RAD] [--floor-beams N] [--own-noise] [--alphas A]
"""

from __future__ import annotations

import argparse
import tempfile
import time
from pathlib import Path

import numpy as np
from bench_amcl_scenarios import scenarios

HERE = Path(__file__).resolve().parent
OUT = HERE / "amcl" / "tradeoff"
SCALES = np.round(np.exp(np.linspace(np.log(0.25), np.log(4.0), 33)), 4)


def step_nees(path: Path, sessions: int, seed: int, workers: int) -> np.ndarray:
    """Every driving step's NEES of AMCL's actual error against the plan's covariance."""
    from tmpnav import pipeline
    from tmpnav.execution.consistency import planned_nees
    from tmpnav.execution.localisers import Localisation
    from tmpnav.execution.result import execute
    from tmpnav.execution.site import SiteNoise
    from tmpnav.scenario.nav2_params import AmclParams

    report = pipeline.plan(path, pipeline.PlanOptions.of(accept_risk=True))
    localisation = Localisation("amcl", AmclParams(), SiteNoise.parse("typical"))
    result = execute(report, sessions, seed, workers, localisation)
    rows = np.concatenate(list(result.consistency.values())) if result.consistency else np.zeros((0, 8))
    nees = planned_nees(rows)
    return nees[np.isfinite(nees)]


def with_localiser(
    path: Path,
    prediction_noise: bool,
    information: float | None,
    heading_blur: float | None = None,
    floor_beams: float | None = None,
    own_noise: bool = False,
    alphas: float | None = None,
) -> None:
    """The scenario at ``path`` with its localiser predicting with AMCL's motion model at nav2's
    defaults (``prediction_noise``), and with the information share ``information``, the
    ``heading_blur`` (rad) and the ``floor_beams`` where given; with ``own_noise`` predicting with
    the robots' own motion noise (models.motion_noise as nav2's alphas: the model before AMCL's
    was the default); with ``alphas`` predicting with all four of nav2's alphas at that value."""
    import yaml

    doc = yaml.safe_load(path.read_text())
    localiser = doc["models"]["range_sensor"]["localiser"]
    if prediction_noise:
        localiser["prediction_noise"] = {}
    if information is not None:
        localiser["information"] = information
    if heading_blur is not None:
        localiser["heading_blur"] = heading_blur
    if floor_beams is not None:
        localiser["floor_beams"] = floor_beams
    if own_noise:
        from tmpnav.scenario.load import load

        a1, a2, a3, a4 = load(path).models.motion_noise  # W = diag(a1 v² + a2 w², a3 v² + a4 w²)
        localiser["prediction_noise"] = {"alpha1": a4, "alpha2": a3, "alpha3": a1, "alpha4": a2}
    if alphas is not None:
        localiser["prediction_noise"] = {f"alpha{i}": alphas for i in (1, 2, 3, 4)}
    path.write_text(yaml.safe_dump(doc, sort_keys=False))


def curve(nees: np.ndarray) -> list[tuple[float, float, float]]:
    """(k, median NEES, share beyond 3 sigma) with the predicted std scaled by k."""
    return [(float(k), float(np.median(nees) / k**2), float(np.mean(nees / k**2 > 9.0))) for k in SCALES]


def both_met(rows: list[tuple[float, float, float]]) -> str:
    """The range of k meeting both targets, in words."""
    ok = [k for k, med, beyond in rows if 1.0 <= med <= 4.0 and beyond <= 0.05]
    return f"k {min(ok):.2f}-{max(ok):.2f}" if ok else "none"


def _rows(csv: Path) -> list[tuple[float, float, float]]:
    k, median, beyond = np.loadtxt(csv, delimiter=",", skiprows=1, unpack=True)
    return list(zip(k.tolist(), median.tolist(), beyond.tolist(), strict=True))


def plot(folder: Path = OUT) -> Path:
    """``folder``/tradeoff.png: each scenario's median NEES and share beyond 3 sigma against k."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, (left, right) = plt.subplots(1, 2, figsize=(12, 4.8))
    for csv in sorted(folder.glob("*.csv")):
        k, median, beyond = np.loadtxt(csv, delimiter=",", skiprows=1, unpack=True)
        left.plot(k, median, label=csv.stem)
        right.plot(k, 100 * beyond, label=csv.stem)
    left.axhspan(1.0, 4.0, color="g", alpha=0.12, label="target: 1-4")
    right.axhspan(0.0, 5.0, color="g", alpha=0.12, label="target: at most 5%")
    for ax, what in ((left, "median NEES against k² P"), (right, "driving steps beyond 3 sigma [%]")):
        ax.axvline(1.0, color="k", lw=0.8, ls=":")
        ax.set_xscale("log")
        ax.set_xticks([0.25, 0.5, 1.0, 2.0, 4.0], ["0.25", "0.5", "1", "2", "4"], minor=False)
        ax.set_xticks([], minor=True)
        ax.set_xlabel("k: the plan's predicted std scaled by (1: the model as it plans)")
        ax.set_ylabel(what)
        ax.grid(True, which="both", alpha=0.3)
    left.set_yscale("log")
    right.legend(fontsize=8)
    met = [csv.stem for csv in sorted(folder.glob("*.csv")) if both_met(_rows(csv)) != "none"]
    verdict = f"a k meets both targets on {', '.join(met)}" if met else "no k meets both targets on any scenario"
    fig.suptitle(f"nav2's AMCL against the plan's beliefs scaled by k ({folder.name})\n{verdict}")
    fig.tight_layout()
    out = folder / "tradeoff.png"
    fig.savefig(out, dpi=100)
    return out


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--sessions", type=int, default=4)
    parser.add_argument("--seed", type=int, default=300)
    parser.add_argument("--workers", type=int, default=2)
    parser.add_argument("--only", nargs="*", default=None)
    parser.add_argument("--plot-only", action="store_true", help="draw tradeoff.png from the CSVs written before")
    parser.add_argument(
        "--prediction-noise",
        action="store_true",
        help="plan with AMCL's own motion model in the beliefs (localiser.prediction_noise: {}, nav2's defaults); "
        "results in amcl/tradeoff/prediction-noise/",
    )
    parser.add_argument(
        "--information",
        type=float,
        default=None,
        help="the localiser's information share in every copy (default: the shipped)",
    )
    parser.add_argument(
        "--heading-blur", type=float, default=None, help="the localiser's heading_blur (rad) in every copy"
    )
    parser.add_argument("--floor-beams", type=float, default=None, help="the localiser's floor_beams in every copy")
    parser.add_argument(
        "--own-noise", action="store_true", help="predict with the robots' own motion noise, not AMCL's alphas"
    )
    parser.add_argument(
        "--alphas", type=float, default=None, help="predict with all four of nav2's alphas at this value"
    )
    args = parser.parse_args()
    variant = [
        *(["prediction-noise"] if args.prediction_noise else []),
        *([f"information-{args.information:g}"] if args.information is not None else []),
        *([f"heading-blur-{args.heading_blur:g}"] if args.heading_blur is not None else []),
        *([f"floor-beams-{args.floor_beams:g}"] if args.floor_beams is not None else []),
        *(["own-noise"] if args.own_noise else []),
        *([f"alphas-{args.alphas:g}"] if args.alphas is not None else []),
    ]
    folder = OUT / "-".join(variant) if variant else OUT  # the shipped model's in OUT itself
    if args.plot_only:
        print(f"wrote {plot(folder)}")
        return
    folder.mkdir(parents=True, exist_ok=True)
    table = []
    with tempfile.TemporaryDirectory() as tmpdir:
        for name, path in scenarios(Path(tmpdir)).items():
            if args.only and name not in args.only:
                continue
            if (
                args.prediction_noise
                or args.own_noise
                or any(v is not None for v in (args.information, args.heading_blur, args.floor_beams, args.alphas))
            ):
                with_localiser(
                    path,
                    args.prediction_noise,
                    args.information,
                    args.heading_blur,
                    args.floor_beams,
                    args.own_noise,
                    args.alphas,
                )
            started = time.perf_counter()
            nees = step_nees(path, args.sessions, args.seed, args.workers)
            rows = curve(nees)
            lines = ["k,median_nees,beyond_3_sigma"] + [f"{k:.4f},{m:.4f},{b:.4f}" for k, m, b in rows]
            (folder / f"{name}.csv").write_text("\n".join(lines) + "\n")
            at1 = rows[len(SCALES) // 2]  # k = 1: the model as it plans
            least = next((k for k, _, b in rows if b <= 0.05), float("nan"))
            most = max((k for k, m, _ in rows if m >= 1.0), default=float("nan"))
            table.append(
                f"{name:28s} {nees.size:6d}  {at1[1]:6.2f}  {100 * at1[2]:5.1f}%  "
                f"{least:6.2f}  {most:6.2f}  {both_met(rows):12s}  {time.perf_counter() - started:6.0f} s"
            )
            print(table[-1], flush=True)
    print(
        "scenario                      steps  median NEES at k=1  beyond 3 sigma  least k with <=5% beyond  "
        "most k with median >=1  both met  time"
    )
    print("\n".join(table))
    print(f"wrote {plot(folder)}")


if __name__ == "__main__":
    main()
