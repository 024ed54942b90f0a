"""``tmpnav serve``: a site held warm behind HTTP (docs/serve.md).

The pipeline of the command line, as a service: :mod:`site` (the scenario loaded once, planned
and revised by the real pipeline), :mod:`store` (plans and revisions on disk, reloaded at
start), :mod:`service` (searches in the background, updates in order), :mod:`events` (server-sent
events), :mod:`app` (the FastAPI routes), :mod:`guard` (token, size limit), :mod:`view` (the
live view's page). Needs the ``serve`` extra: ``pip install 'tmpnav[serve]'``.
"""

from __future__ import annotations

import ipaddress
import socket
from collections.abc import Callable
from pathlib import Path

from tmpnav.errors import InputError

__all__ = ["bind", "serve"]


def is_loopback(host: str) -> bool:
    """Whether ``host`` names only this machine (127.0.0.0/8, ::1, localhost)."""
    if host == "localhost":
        return True
    try:
        return ipaddress.ip_address(host).is_loopback
    except ValueError:
        return False


def bind(host: str, port: int, token: str | None) -> socket.socket:
    """A listening socket on ``host:port`` (port 0: a free one). Without a token, only a
    loopback address: a planner that anyone on the network could drive is refused."""
    if token is None and not is_loopback(host):
        raise InputError(
            f"--host {host}: without --token the service binds only a loopback address (127.0.0.1, ::1); "
            "give --token to serve other machines"
        )
    if token is not None and not token.strip():
        raise InputError("--token: empty; expected a secret that every request carries")
    family = socket.AF_INET6 if ":" in host else socket.AF_INET
    sock = socket.socket(family, socket.SOCK_STREAM)
    sock.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
    try:
        sock.bind((host, port))
    except OSError as err:
        sock.close()
        raise InputError(f"--host {host} --port {port}: cannot listen there: {err.strerror or err}") from None
    sock.listen(128)
    sock.set_inheritable(True)
    return sock


def serve(
    scenario: Path,
    host: str = "127.0.0.1",
    port: int = 8765,
    token: str | None = None,
    cache_dir: Path | None = None,
    time_limit: float = 300.0,
    max_body: int = 1 << 20,
    ready: Callable[[str, int], None] = lambda host, port: None,
) -> None:
    """Load the site, then serve it until SIGINT or SIGTERM; ``ready`` is told the address."""
    try:
        import uvicorn

        from tmpnav.serve.app import create_app
        from tmpnav.serve.service import Limits, Service
    except ImportError as err:
        raise InputError(
            f"tmpnav serve needs the serve extra ({err.name} is missing): pip install 'tmpnav[serve]'"
        ) from None
    sock = bind(host, port, token)
    service = Service.start(scenario, cache_dir, Limits(time_limit=time_limit, max_body=max_body))
    app = create_app(service, token)
    config = uvicorn.Config(app, log_level="warning", timeout_graceful_shutdown=5, access_log=False)
    server = uvicorn.Server(config)
    ready(host, sock.getsockname()[1])
    server.run(sockets=[sock])
