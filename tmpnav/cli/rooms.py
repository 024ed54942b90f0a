"""``tmpnav rooms``: a scenario skeleton from a ROS map_server map (tmpnav/rooms/)."""

from __future__ import annotations

from pathlib import Path

import click

from tmpnav.cli.commands import cli
from tmpnav.cli.options import FiniteRange, option, report_errors, unwritable, writing
from tmpnav.rooms import MAX_AREA


def _rooms_outputs(ctx: click.Context, param: click.Parameter, value: tuple[Path, ...]) -> dict[str, Path]:
    """``-o`` of ``tmpnav rooms``: at most one .yaml scenario and one picture (.png, .svg,
    ...: see tmpnav.report.FIGURE_FORMATS), writable."""
    from tmpnav.report import figure_format, figure_suffixes

    out: dict[str, Path] = {}
    for path in value:
        kind = "scenario" if path.suffix.lower() in (".yaml", ".yml") else "picture"
        if kind == "picture" and figure_format(path.name) is None:
            raise click.BadParameter(
                f"{path}: expected a .yaml scenario or a picture ({figure_suffixes()})", ctx=ctx, param=param
            )
        if kind in out:
            raise click.BadParameter(f"{path}: a {kind} is written once ({out[kind]})", ctx=ctx, param=param)
        if why := unwritable(path, False):
            raise click.BadParameter(why, ctx=ctx, param=param)
        out[kind] = path
    return out


@cli.command()
@click.argument("map_yaml", metavar="MAP.yaml", type=click.Path(path_type=Path, dir_okay=False))
@option(
    "-o",
    "--output",
    "outputs",
    multiple=True,
    type=click.Path(path_type=Path, dir_okay=False),
    callback=_rooms_outputs,
    default_text="print the scenario, draw nothing",
    help="scenario.yaml to write, and/or a picture (rooms.png, .svg, .pdf, ...): the segmentation over "
    "the map; give -o twice for both.",
)
@option(
    "--min-area",
    type=FiniteRange(min=0, min_open=True),
    default=3.0,
    show_default=True,
    metavar="M2",
    help="Square metres: smaller regions join their neighbour (a closet, a niche) or are left out.",
)
@option(
    "--max-area",
    type=FiniteRange(min=0, min_open=True),
    default=MAX_AREA,
    show_default=True,
    metavar="M2",
    help="Square metres: a larger room is a hall (a warehouse floor, a depot) and is split into places of "
    "at most about this size: aisles between racks, aisle fronts, parts of open floor.",
)
@option(
    "--max-rooms",
    type=click.IntRange(min=1),
    metavar="N",
    default_text="no limit",
    help="Join the least separated rooms down to N rooms; halls are then not split into places.",
)
@report_errors
def rooms(map_yaml: Path, outputs: dict[str, Path], min_area: float, max_area: float, max_rooms: int | None) -> None:
    """Find rooms, places, doors in a ROS map; write a scenario.

    Finds the rooms (distance-transform watershed), splits halls larger than --max-area into
    places along the medial axis of their free space, finds the doors between rooms, the
    connections between places and landmark candidates (pillars, isolated obstacles, door
    frames, corners), and writes a scenario that validates and plans as written: rooms R1..Rn
    and places P1..Pm with polygons, doors, landmarks, a placeholder robot and two goal rooms
    (with halls: two robots and four goal places), with comments saying what to check.
    """
    if max_area <= min_area:
        message = f"{max_area:g} m² is not larger than --min-area {min_area:g} m²"
        raise click.BadParameter(message, param_hint="'--max-area'")
    from tmpnav.rooms.proposal import propose, read_map
    from tmpnav.rooms.segment import SegmentParams
    from tmpnav.rooms.skeleton import save, skeleton, summary
    from tmpnav.rooms_check import verify
    from tmpnav.scenario import display_path
    from tmpnav.shipped import resolve

    spec, grid = read_map(resolve(map_yaml))
    params = SegmentParams(min_area=min_area, max_area=max_area, max_rooms=max_rooms)
    proposal, warnings = verify(propose(spec, grid, params))
    for warning in warnings:  # not expected: the proposal is built to pass
        click.echo(f"warning: {warning}", err=True)
    left_out = [r.name for r in proposal.rooms if not r.reachable]
    if left_out:
        click.echo(
            f"warning: {', '.join(left_out)} left out (as comments): a robot of radius 0.25 m does not reach "
            "them from r1's start (a narrow door, or noise in the map at a doorway)",
            err=True,
        )
    target = outputs.get("scenario")
    text = skeleton(proposal, target)
    found = summary(proposal)
    if target is None:
        click.echo(text, nl=False)
    else:
        with writing(target):
            save(target, text)
        click.echo(f"wrote {target}: {found}")
    if "picture" in outputs:
        from tmpnav.report.rooms_plot import plot_rooms

        with writing(outputs["picture"]):
            plot_rooms(proposal, outputs["picture"], f"{display_path(spec.yaml_path)}: {found}")
        click.echo(f"wrote {outputs['picture']}", err=target is None)
