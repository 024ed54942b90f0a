"""Whether two runs of one scenario planned the same: plan.json and every cost in the cache.

    python benchmarks/compare_plans.py OUT_A OUT_B CACHE_A CACHE_B

plan.json is compared without its timing fields (keys naming a time, seconds, elapsed, load,
stage or timings, and the search's history); numbers are equal or within 1e-9 relative. The
oracle's cache entries are matched by their values, since their keys hold the digest of the
code (tmpnav.oracle.keys.code_version): a speed-up changes every key and no value. The scan
information tables and localisability maps beside the roadmaps are compared array by array.
Exits 1 on any difference.
"""

from __future__ import annotations

import json
import sqlite3
import sys
from collections import Counter
from pathlib import Path
from typing import Any

import numpy as np

TIMING = ("time", "timing", "seconds", "elapsed", "load", "stage", "directory", "file", "history")


def strip(value: Any) -> Any:
    """``value`` without the keys that name timings or where the run wrote."""
    if isinstance(value, dict):
        return {k: strip(v) for k, v in value.items() if not any(t in k.lower() for t in TIMING)}
    if isinstance(value, list):
        return [strip(v) for v in value]
    return value


def differences(a: Any, b: Any, path: str = "") -> list[str]:
    """Where ``a`` and ``b`` differ (floats within 1e-9 relative count as equal)."""
    if isinstance(a, dict) and isinstance(b, dict):
        out = [f"{path}/{k} missing" for k in set(a) ^ set(b)]
        return out + [d for k in set(a) & set(b) for d in differences(a[k], b[k], f"{path}/{k}")]
    if isinstance(a, list) and isinstance(b, list):
        if len(a) != len(b):
            return [f"{path}: {len(a)} against {len(b)} items"]
        return [d for i, (x, y) in enumerate(zip(a, b, strict=True)) for d in differences(x, y, f"{path}[{i}]")]
    if isinstance(a, float) and isinstance(b, float) and abs(a - b) <= 1e-9 * max(abs(a), abs(b)):
        return []
    return [] if a == b else [f"{path}: {a!r} against {b!r}"]


def cache_values(cache: Path) -> list[str]:
    """The oracle cache's values (JSON text)."""
    with sqlite3.connect(cache / "oracle-v1.sqlite3") as conn:
        return [bytes(v).decode() for (v,) in conn.execute("SELECT value FROM entries")]


def compare_cache(a: Path, b: Path) -> list[str]:
    """The values of one cache with no equal in the other (timing fields aside)."""
    va, vb = Counter(cache_values(a)), Counter(cache_values(b))
    left_a, left_b = list((va - vb).elements()), list((vb - va).elements())
    unmatched = []
    for text in left_a:
        x = strip(json.loads(text))
        match = next((y for y in left_b if not differences(x, strip(json.loads(y)))), None)
        if match is None:
            unmatched.append(text[:120])
        else:
            left_b.remove(match)
    return unmatched + [text[:120] for text in left_b]


def compare_tables(a: Path, b: Path) -> list[str]:
    """The scan and localisability tables of the two caches that differ."""
    out = []
    for kind in ("scans", "localisability"):
        fa, fb = sorted((a / "roadmaps").glob(f"*.{kind}.npz")), sorted((b / "roadmaps").glob(f"*.{kind}.npz"))
        if len(fa) != len(fb):
            out.append(f"{kind}: {len(fa)} against {len(fb)} files")
            continue
        for x, y in zip(fa, fb, strict=True):
            za, zb = np.load(x), np.load(y)
            for name in sorted(set(za.files) - {"header"}):
                if name not in zb.files or not np.array_equal(za[name], zb[name], equal_nan=za[name].dtype.kind == "f"):
                    out.append(f"{kind}: {name} differs")
    return out


def main() -> None:
    """Compare the two runs; print what differs."""
    out_a, out_b, cache_a, cache_b = (Path(p) for p in sys.argv[1:5])
    plan = differences(
        strip(json.loads((out_a / "plan.json").read_text())), strip(json.loads((out_b / "plan.json").read_text()))
    )
    cache = compare_cache(cache_a, cache_b)
    tables = compare_tables(cache_a, cache_b)
    print(f"plan.json: {len(plan)} differences {plan[:5]}")
    print(f"oracle cache: {len(cache_values(cache_a))} entries, {len(cache)} without an equal {cache[:2]}")
    print(f"scan and localisability tables: {len(tables)} differences {tables[:3]}")
    sys.exit(1 if plan or cache or tables else 0)


if __name__ == "__main__":
    main()
