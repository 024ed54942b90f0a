"""A real service of configs/two-rooms.yaml per test file, on a free port and a cache directory of
its own."""

from __future__ import annotations

from collections.abc import Iterator

import pytest

pytest.importorskip("fastapi", reason="tmpnav serve's tests need the serve extra: pip install 'tmpnav[serve]'")

from tests.serve.server import Server
from tmpnav.client import Client


@pytest.fixture(scope="module")
def server(tmp_path_factory: pytest.TempPathFactory) -> Iterator[Server]:
    running = Server("configs/two-rooms.yaml", tmp_path_factory.mktemp("serve-cache"))
    try:
        yield running
    finally:
        running.stop()


@pytest.fixture(scope="module")
def client(server: Server) -> Client:
    return Client(server.url, timeout=600)


@pytest.fixture(scope="module")
def first(client: Client) -> dict:
    """The scenario's first plan, made once per file."""
    return client.plan()
