"""`mani hands`: list the built-in hands, or write an interactive 3D view of one (offline HTML, plotly inlined).

Examples:
    mani hands
    mani hands show allegro --html allegro.html
"""

from __future__ import annotations

import argparse
from typing import Any

EXIT_OK, EXIT_USAGE = 0, 2


def register(subparsers: Any) -> None:
    """Add ``hands`` (and ``hands show NAME``) to ``mani``."""
    p = subparsers.add_parser(
        "hands",
        help="list built-in robot hands, or show one in 3D",
        description=__doc__,
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    sub = p.add_subparsers(dest="hands_command", metavar="{show}")
    show = sub.add_parser("show", help="write an interactive 3D view of a hand at rest (HTML, offline)")
    show.add_argument("name", help="built-in hand name (see `mani hands`)")
    show.add_argument("--html", required=True, help="output HTML file")
    show.set_defaults(func=run_show)
    p.set_defaults(func=run_list)


def run_list(args: argparse.Namespace) -> int:
    """Print one row per built-in hand: DoF, fingertips, spheres, self-collision pairs."""
    from manifoundation.core.robots import get_hand, list_hands
    from manifoundation.core.robots.registry import ALIASES

    header = f"{'name':<14} {'dof':>4} {'tips':>4} {'spheres':>7} {'pairs':>6}  fingertip links"
    print(header)
    print("-" * len(header))
    for name in list_hands(aliases=True):
        if name in ALIASES:
            print(f"{name:<14} alias of {ALIASES[name]}")
            continue
        h = get_hand(name)
        tips = ", ".join(h.fingertip_links)
        counts = f"{h.dof:>4} {h.num_fingertips:>4} {len(h.sphere_radii):>7} {len(h.self_collision_pairs):>6}"
        print(f"{name:<14} {counts}  {tips}")
    print("leap_hand: the original LEAP Hand (its joint names and zero pose); leap_kaizen: ghand's LEAP V1 KAIZEN")
    return EXIT_OK


def run_show(args: argparse.Namespace) -> int:
    """Write ``args.html`` with the hand ``args.name`` at rest."""
    from manifoundation.core.robots import UnknownHand, get_hand
    from manifoundation.core.robots.view import hand_figure

    try:
        hand = get_hand(args.name)
    except UnknownHand as e:
        print(f"error: {e.args[0]}")
        return EXIT_USAGE
    fig = hand_figure(hand)
    fig.write_html(args.html, include_plotlyjs=True, full_html=True)
    print(f"wrote {args.html}")
    return EXIT_OK
