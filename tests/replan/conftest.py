"""The replan tests' shift (data/hall.yaml) planned once per session, and how they run tmpnav."""

from __future__ import annotations

import json
import subprocess
import sys
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import pytest

ROOT = Path(__file__).resolve().parents[2]
HALL = ROOT / "tests" / "replan" / "data" / "hall.yaml"


def tmpnav(*args: str | Path) -> subprocess.CompletedProcess[str]:
    return subprocess.run(
        [sys.executable, "-m", "tmpnav", *map(str, args)], capture_output=True, text=True, cwd=ROOT, timeout=900
    )


@dataclass(frozen=True)
class Planned:
    """The shift, its first plan (plan.json) and the cache both were made with."""

    scenario: Path
    plan: Path
    cache: Path

    def doc(self) -> dict[str, Any]:
        return dict(json.loads(self.plan.read_text()))

    def replan(
        self, tmp: Path, state: str, *more: str | Path, plan: Path | None = None
    ) -> subprocess.CompletedProcess[str]:
        """``tmpnav replan`` of ``plan`` (the first plan by default) from ``state``, into tmp/out."""
        (tmp / "state.yaml").write_text(state)
        return tmpnav(
            "replan", self.scenario, "--plan", plan or self.plan, "--state", tmp / "state.yaml", "--cache-dir",
            self.cache, "-o", tmp / "out", *more,
        )  # fmt: skip


@pytest.fixture(scope="session")
def hall(tmp_path_factory: pytest.TempPathFactory) -> Planned:
    tmp = tmp_path_factory.mktemp("hall")
    proc = tmpnav("plan", HALL, "-q", "--cache-dir", tmp / "cache", "-o", tmp / "first")
    assert proc.returncode == 0, proc.stderr
    return Planned(HALL, tmp / "first" / "plan.json", tmp / "cache")


def moves_of(doc: dict[str, Any], robot: str) -> list[dict[str, Any]]:
    """A robot's moves in a plan.json's schedule."""
    return list(doc["schedule"]["robots"][robot]["moves"])


def read_revision(tmp: Path) -> dict[str, Any]:
    return dict(json.loads((tmp / "out" / "plan.json").read_text()))
