"""`mani robots`: register a hand (an archive, folder or URDF/MJCF, cut at a palm), list, show or delete hands."""

from __future__ import annotations

import argparse
import json
from pathlib import Path
from typing import Any

from manifoundation.cli import common


def register(subparsers: argparse._SubParsersAction[argparse.ArgumentParser]) -> None:
    """Add ``mani robots`` with ``list`` (default), ``add``, ``show`` and ``delete``."""
    parser = common.command_parser(
        subparsers,
        "robots",
        "List the hands this key may use (default), register one, show one, or delete one.",
        "mani robots add g1.zip --palm right_hand_palm_link   |   mani robots show g1   |   mani robots delete g1",
        run_list,
    )
    common.add_connection_args(parser)
    actions = parser.add_subparsers(dest="robots_command", metavar="ACTION")

    listing = common.command_parser(
        actions, "list", "List built-in and registered hands.", "mani robots list", run_list
    )
    common.add_connection_args(listing)

    add = common.command_parser(
        actions,
        "add",
        "Register a hand: a zip/tar of a URDF or MJCF with its meshes, a folder (zipped for you), or a description "
        "alone (primitives only). --palm cuts the hand from a whole robot.",
        "mani robots add g1_hand.zip --palm right_hand_palm_link --name g1-dex3",
        run_add,
    )
    add.add_argument("source", type=Path, metavar="SOURCE", help="archive, folder, .urdf or .xml/.mjcf file")
    add.add_argument("--palm", help="the link the floating 6-DoF base attaches to (default: the root)")
    add.add_argument("--fingertips", nargs="+", metavar="LINK", help="fingertip links (default: the leaf links)")
    add.add_argument("--name", help="register under this name (default: the file or folder name)")
    add.add_argument("--description", help="the archive member to load when it holds several descriptions")
    add.add_argument(
        "--tip-offsets", type=json.loads, help="JSON (m, 3): contact points in the fingertip link frames, metres"
    )
    add.add_argument("--rest", type=json.loads, help='JSON {"joint": value}: the rest pose')
    add.add_argument("--approach-axis", type=float, nargs=3, metavar=("X", "Y", "Z"), help="palm-frame approach")
    common.add_connection_args(add)

    show = common.command_parser(
        actions, "show", "Show one hand and its build report.", "mani robots show g1", run_show
    )
    show.add_argument("name", metavar="NAME")
    common.add_connection_args(show)

    delete = common.command_parser(
        actions, "delete", "Remove a hand this key registered.", "mani robots delete g1", run_delete
    )
    delete.add_argument("name", metavar="NAME")
    common.add_connection_args(delete)


def robot_lines(robot: Any) -> list[str]:
    """A hand and its build report, one fact a line."""
    lines = [
        f"{robot.name}: {'built-in' if robot.builtin else 'registered'}, {robot.dof} DoF"
        + (f", palm {robot.palm}" if robot.palm else "")
        + (f", {robot.format}" if robot.format else ""),
        f"fingertips: {', '.join(robot.fingertips)}",
        f"joints: {', '.join(robot.joint_names)}",
    ]
    if robot.num_spheres is not None:
        lines.append(f"collision spheres: {robot.num_spheres}")
    if robot.surface_points is not None:
        lines.append(f"hand point cloud: {robot.surface_points} points")
    if robot.pad_area_cm2:
        lines.append("pad areas: " + ", ".join(f"{a:.1f} cm²" for a in robot.pad_area_cm2))
    if robot.meshes is not None:
        lines.append(f"mesh files read: {robot.meshes}")
    if robot.registration_s is not None:
        lines.append(f"built in {robot.registration_s:.2f} s")
    lines += [f"coupling: {c}" for c in robot.couplings]
    lines += [f"ignored: {i}" for i in robot.ignored]
    lines += [f"warning: {w}" for w in robot.warnings]
    if robot.view_url:
        lines.append(f"view: {robot.view_url}")
    return lines


@common.run_guarded
def run_list(args: argparse.Namespace) -> int:
    """Run ``mani robots [list]``."""
    with common.client_factory(args) as client:
        robots = client.robots()
    if args.json:
        common.print_json([r.model_dump(mode="json", exclude_none=True) for r in robots])
        return common.EXIT_OK
    from rich.table import Table

    table = Table(title=f"hands ({len(robots)})")
    for column in ("name", "kind", "DoF", "palm", "fingertips", "spheres"):
        table.add_column(column, overflow="fold")
    for r in robots:
        kind = "built-in" if r.builtin else "registered"
        spheres = "" if r.num_spheres is None else str(r.num_spheres)
        table.add_row(r.name, kind, str(r.dof), r.palm or "", ", ".join(r.fingertips), spheres)
    common.stdout_console().print(table)
    return common.EXIT_OK


@common.run_guarded
def run_add(args: argparse.Namespace) -> int:
    """Run ``mani robots add``."""
    with common.client_factory(args) as client:
        robot = client.add_robot(
            args.source, palm=args.palm, fingertips=args.fingertips, name=args.name, description=args.description,
            tip_offsets=args.tip_offsets, rest=args.rest, approach_axis=args.approach_axis,
        )  # fmt: skip
    if args.json:
        common.print_json(robot.model_dump(mode="json", exclude_none=True))
    else:
        print("\n".join(robot_lines(robot)))
    return common.EXIT_OK


@common.run_guarded
def run_show(args: argparse.Namespace) -> int:
    """Run ``mani robots show``."""
    with common.client_factory(args) as client:
        robot = client.robot(args.name)
    if args.json:
        common.print_json(robot.model_dump(mode="json", exclude_none=True))
    else:
        print("\n".join(robot_lines(robot)))
    return common.EXIT_OK


@common.run_guarded
def run_delete(args: argparse.Namespace) -> int:
    """Run ``mani robots delete``."""
    with common.client_factory(args) as client:
        client.delete_robot(args.name)
    if args.json:
        common.print_json({"deleted": args.name})
    else:
        print(f"deleted {args.name}")
    return common.EXIT_OK
