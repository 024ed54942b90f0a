"""``tmpnav serve``: the planning service (tmpnav.serve, docs/serve.md)."""

from __future__ import annotations

from pathlib import Path

import click

from tmpnav.cli.commands import cli
from tmpnav.cli.options import CACHE_DIR_OPTION, SCENARIO_ARG, option, report_errors, seconds_option


@cli.command()
@SCENARIO_ARG
@option(
    "--host",
    default="127.0.0.1",
    show_default=True,
    help="The address to listen on; without --token only a loopback address.",
)
@option(
    "--port",
    type=click.IntRange(0, 65535),
    default=8765,
    show_default=True,
    help="The port to listen on (0: a free one, printed at start).",
)
@option(
    "--token",
    envvar="TMPNAV_SERVE_TOKEN",
    default=None,
    default_text="none: loopback only",
    help="A secret every request must carry (Authorization: Bearer TOKEN); also $TMPNAV_SERVE_TOKEN.",
)
@CACHE_DIR_OPTION
@seconds_option(
    "--time-limit", default=300.0, show_default=True, help="Seconds a search may run before the service cancels it."
)
@option(
    "--max-body",
    type=click.IntRange(1024),
    default=1 << 20,
    show_default=True,
    metavar="BYTES",
    help="The largest request body accepted.",
)
@report_errors
def serve(
    scenario: Path, host: str, port: int, token: str | None, cache_dir: Path | None, time_limit: float, max_body: int
) -> None:
    """Serve a site over HTTP: plans, revisions, a live view.

    Plan shifts of SCENARIO's site, post the team's state and get each revision, and watch
    them live in a browser at the printed address (docs/serve.md).

    The site is loaded once and kept warm; plans and revisions are kept in the cache
    directory and reloaded at start. Without --token it listens on loopback only.
    End it with Ctrl-C. Needs the serve extra: pip install 'tmpnav[serve]'.
    """
    import tmpnav.deadline
    from tmpnav.serve import serve as run

    tmpnav.deadline.COMMAND_STARTED = None  # each plan served has its own clock (--time-limit here is the service's)

    def ready(bound_host: str, bound_port: int) -> None:
        shown = f"[{bound_host}]" if ":" in bound_host else bound_host
        click.echo(f"tmpnav serve: {scenario} at http://{shown}:{bound_port}/ (Ctrl-C to end)", err=True)

    run(scenario, host, port, token, cache_dir, time_limit, max_body, ready)
