"""How long a scenario file just under the cap of YAML values takes to read (tmpnav.scenario.yamlio).

    python benchmarks/bench_yaml.py -o benchmarks/yaml

A file of 390,000 values (130,000 two-number walls: a large plain scenario, just under the
default cap of 500,000), read by libyaml (the C loader, when PyYAML has it) and by the
pure-Python reader (the fallback; a fifth of that file, under a cap of 100,000). Writes
`yaml.txt`: the median of three reads for each.
"""

from __future__ import annotations

import argparse
import os
import platform
import statistics
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from tmpnav.scenario import yamlio  # noqa: E402


def seconds(walls: int) -> float:
    text = "walls: [" + ", ".join(["[0, 1]"] * walls) + "]\n"
    runs = []
    for _ in range(3):
        start = time.perf_counter()
        data, _ = yamlio.read_yaml(text)
        runs.append(time.perf_counter() - start)
        assert len(data["walls"]) == walls
    return statistics.median(runs)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("-o", "--output", type=Path, required=True)
    args = ap.parse_args()
    args.output.mkdir(parents=True, exist_ok=True)
    lines = []
    if yamlio.Yaml12CLoader is not None:
        lines.append(f"libyaml: 130,000 walls (390,003 values): {seconds(130_000):.2f} s")
    else:
        lines.append("libyaml: not in this PyYAML")
    yamlio.Yaml12CLoader = None
    os.environ["TMPNAV_MAX_YAML_NODES"] = "100000"
    lines.append(f"pure-Python reader: 26,000 walls (78,003 values): {seconds(26_000):.2f} s")
    lines.append(f"machine: {platform.processor() or platform.machine()}, python {platform.python_version()}")
    lines.append(f"command: python benchmarks/bench_yaml.py -o {args.output}")
    text = "\n".join(lines) + "\n"
    (args.output / "yaml.txt").write_text(text)
    print(text, end="")


if __name__ == "__main__":
    main()
