"""Fixtures of the oracle tests."""

from __future__ import annotations

import pytest

from tests.oracle.support import make_two_rooms
from tmpnav.oracle.executors import OracleContext


@pytest.fixture(scope="session")
def two_rooms() -> OracleContext:
    return make_two_rooms()
