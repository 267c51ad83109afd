"""`mani synthesize`: one object file in, contacts + forces + hand pose out (table, JSON, or a 3D view)."""

from __future__ import annotations

import argparse
import json
import time
from pathlib import Path
from typing import TYPE_CHECKING, Any

from manifoundation.cli import common

if TYPE_CHECKING:
    from manifoundation.contract import SynthesisResult

TASK_HELP = (
    "what to do: 'force_closure' (hold it; default), 'delta:TX,TY,TZ[,QW,QX,QY,QZ]' (move by a translation in m "
    "and a rotation), 'wrench:FX,FY,FZ,TX,TY,TZ', 'targets:FILE.npy|.npz' (target point cloud, one row per "
    "point), or '@FILE.json' (a task in its JSON form)"
)


def register(subparsers: argparse._SubParsersAction[argparse.ArgumentParser]) -> None:
    """Add ``mani synthesize``."""
    parser = common.command_parser(
        subparsers,
        "synthesize",
        "Synthesise contacts, forces and a hand pose for one object and wait for the answer.",
        "mani synthesize examples/data/box.npz --hand leap --task delta:0,0,0.05 --method direct_grasp "
        "--out result.json --view result.html   (over gRPC: add --grpc 127.0.0.1:50051)",
        run,
    )
    parser.add_argument(
        "file",
        type=Path,
        metavar="FILE",
        help="object: .npz (points[, normals, region_mask]), .ply/.obj/.stl mesh, an ObjectIn .json,"
        " or a whole SynthesisRequest .json (then the request options below are ignored)",
    )
    add_request_args(parser)
    out = parser.add_argument_group("output")
    out.add_argument("--out", type=Path, help="write the result as JSON to this file")
    out.add_argument("--view", type=Path, help="write an interactive 3D view (HTML, works offline) to this file")
    out.add_argument("--open", action="store_true", help="open the --view file in the browser")
    out.add_argument("--require-success", action="store_true", help="exit 1 when no proposal passes verification")
    common.add_connection_args(parser, grpc=True)


def add_request_args(parser: argparse.ArgumentParser) -> None:
    """The options that make a request from an object file (shared with ``mani batch submit``)."""
    req = parser.add_argument_group("request")
    req.add_argument("--hand", default="leap", help="built-in or registered hand name (default %(default)s); "
                     "'none' for a deformable's contacts and motions for any gripper")
    req.add_argument("--simulate", action=argparse.BooleanOptionalAction, default=None,
                     help="rigid objects: each answer is tested in MuJoCo (six pushes, or the executed motion for a "
                     "delta task) and 'ok' means it held; --simulate searches candidates until one holds, "
                     "--no-simulate skips the test (simulate: unset, true, false)")
    req.add_argument("--rollout", action="store_true",
                     help="deformables: simulate the answer and judge it by the shape metric (simulate_rollout)")
    req.add_argument("--corrections", type=int, default=0, metavar="C",
                     help="with --rollout: up to C more rollouts correcting a missing answer's motions "
                     "(rollout_corrections)")
    req.add_argument("--urdf", type=Path, help="an inline URDF hand instead of --hand (needs --fingertips)")
    req.add_argument("--fingertips", help="comma-separated fingertip links of the --urdf hand")
    req.add_argument("--task", default="force_closure", help=TASK_HELP)
    req.add_argument(
        "--method",
        default="auto",
        choices=("auto", "network", "contacts", "direct_grasp", "random_contacts"),
        help="how contacts are found (default %(default)s; direct_grasp needs no trained model)",
    )
    req.add_argument("--proposals", type=int, default=1, help="hand proposals to return (default 1)")
    req.add_argument("--stop-after", type=int, metavar="N",
                     help="stop once N proposals are verified: the later ones are not refined (stop_after_verified)")
    req.add_argument("--seed", type=int, default=0, help="sampling seed (default 0)")
    req.add_argument("--timeout", type=float, default=30.0, help="seconds to wait for the answer (default 30)")
    req.add_argument("--max-iterations", type=int, default=100, help="refinement iterations (default 100)")
    req.add_argument("--no-refine", action="store_true", help="skip the SOCP refinement (initial pose only)")
    req.add_argument("--heatmap", action="store_true", help="return the contact heatmap (coloured in --view)")
    req.add_argument("--points", type=int, default=2048, help="points sampled from a mesh file (default 2048)")
    req.add_argument("--friction", type=float, help="friction coefficient μ (default: the service's, 0.5)")


def parse_task(text: str) -> Any:
    """A task model from the ``--task`` syntax (see `TASK_HELP`)."""
    import numpy as np

    from manifoundation.sdk import delta_pose, force_closure, target_points, wrench
    from manifoundation.sdk.tasks import as_task

    kind, _, rest = text.partition(":")
    if text.startswith("@"):
        return as_task(json.loads(Path(text[1:]).read_text()))
    numbers = [float(v) for v in rest.split(",")] if rest and kind in ("delta", "wrench") else []
    if kind == "force_closure":
        return force_closure()
    if kind == "delta" and len(numbers) in (3, 7):
        return delta_pose(numbers[:3], numbers[3:] or None)
    if kind == "wrench" and len(numbers) == 6:
        return wrench(numbers[:3], numbers[3:])
    if kind == "targets" and rest:
        path = Path(rest)
        if path.suffix == ".npz":
            with np.load(path, allow_pickle=False) as data:
                key = "targets" if "targets" in data.files else data.files[0]
                return target_points(data[key])
        return target_points(np.load(path, allow_pickle=False))
    raise ValueError(f"--task {text!r}: not understood; {TASK_HELP}")


def build_request(args: argparse.Namespace, path: Path | None = None) -> Any:
    """The `SynthesisRequest` a command line describes, for ``path`` (default ``args.file``).

    A ``.json`` file holding a whole request is used as it is; any other file is an object, and the request
    options of the command line make the rest.
    """
    path = args.file if path is None else path
    from manifoundation.contract import SynthesisRequest
    from manifoundation.sdk import make_request, object_from_file
    from manifoundation.sdk.errors import local_validation_error

    if path.suffix.lower() == ".json":
        data = json.loads(path.read_text())
        if isinstance(data, dict) and {"object", "task"} <= set(data):
            import pydantic

            try:
                return SynthesisRequest.model_validate(data)
            except pydantic.ValidationError as exc:
                raise local_validation_error(exc) from exc
    fields: dict[str, Any] = {}
    if args.friction is not None:
        fields["properties"] = {"friction": args.friction}
    obj = object_from_file(path, args.points, seed=args.seed, **fields)
    robot: Any = None if args.hand == "none" else args.hand
    if args.urdf is not None:
        if not args.fingertips:
            raise ValueError("--urdf needs --fingertips (comma-separated link names)")
        robot = {"urdf": args.urdf.read_text(), "fingertips": args.fingertips.split(",")}
    return make_request(
        obj,
        parse_task(args.task),
        robot,
        method=args.method,
        num_proposals=args.proposals,
        stop_after_verified=args.stop_after,
        seed=args.seed,
        timeout=args.timeout,
        max_iterations=args.max_iterations,
        refine=not args.no_refine,
        return_heatmap=args.heatmap,
        return_hand_mesh=getattr(args, "view", None) is not None,  # --view draws the posed hand's meshes
        simulate_rollout=args.rollout,
        rollout_corrections=args.corrections,
        simulate=args.simulate,
    )


def wait_with_progress(job: Any, timeout: float, show: bool) -> Any:
    """Poll a job until it ends, showing its stage and progress on stderr; returns its last `JobPublic`."""
    from rich.progress import BarColumn, Progress, SpinnerColumn, TextColumn, TimeElapsedColumn

    from manifoundation.sdk import TimeoutError
    from manifoundation.sdk.retry import poll_delays

    console = common.stderr_console()
    deadline = time.monotonic() + timeout
    columns = (SpinnerColumn(), TextColumn("{task.description}"), BarColumn(), TimeElapsedColumn())
    with Progress(*columns, console=console, disable=not show, transient=True) as progress:
        bar = progress.add_task(f"job {job.id}: queued", total=1.0)
        for delay in poll_delays(cap=0.5):
            status = job.status()
            stage = status.progress.stage.value
            if status.progress.iteration is not None:
                stage += f" (iteration {status.progress.iteration}/{status.progress.max_iterations or '?'})"
            progress.update(
                bar, description=f"job {job.id}: {status.state.value}, {stage}", completed=status.progress.fraction
            )
            if status.state.terminal:
                return status
            left = deadline - time.monotonic()
            if left <= 0:
                raise TimeoutError(f"job {job.id} still {status.state.value} after {timeout:g} s", job_id=job.id)
            time.sleep(min(delay, left))
    raise AssertionError("unreachable")


def result_table(result: SynthesisResult) -> Any:
    """A rich table of the proposals' quality figures."""
    from rich import box
    from rich.table import Table

    title = f"{result.hand or 'contacts for any gripper'} · model {result.model_version}"
    table = Table(title=title, box=box.SIMPLE_HEAD, pad_edge=False, padding=(0, 1, 0, 0))
    if any(p.contact_motions is not None for p in result.proposals):
        return _deformable_rows(table, result)
    # where the simulated test ran, its verdict (held, moved, reached, ...) stands where the refinement's reason is
    tested = any(p.quality.physics is not None for p in result.proposals)
    reason = "physics" if tested else "reason"
    for column in ("#", "ok", reason, "from", "iter", "residual", "tip mm", "pen mm", "ε", "palm x y z (m)"):
        table.add_column(column, justify="left" if column in ("ok", reason, "from") else "right", no_wrap=True)
    for i, p in enumerate(result.proposals):
        q = p.quality
        table.add_row(
            str(i),
            "[green]yes[/]" if q.success else "[red]no[/]",
            q.reason if not tested else "-" if q.physics is None else q.physics.reason,
            p.contact_source or "-",
            str(q.iterations),
            f"{q.wrench_residual:.1e}",
            f"{q.max_tip_distance * 1e3:.1f}",
            f"{q.penetration_depth * 1e3:.1f}",
            "-" if q.epsilon is None else f"{q.epsilon:.3f}",
            "-" if p.palm_position is None else " ".join(f"{v:+.3f}" for v in p.palm_position),
        )
    return table


def _deformable_rows(table: Any, result: SynthesisResult) -> Any:
    """Contacts with post-contact motions: the contacts' source, the motions and the simulated verdict."""
    for column in ("#", "ok", "reason", "contacts", "from", "largest motion (m)", "shape error"):
        table.add_column(column, justify="left" if column in ("ok", "reason", "from") else "right")
    for i, p in enumerate(result.proposals):
        motion = 0.0 if p.contact_motions is None else float((p.contact_motions**2).sum(axis=1).max() ** 0.5)
        table.add_row(str(i), "[green]yes[/]" if p.quality.success else "[red]no[/]", p.quality.reason,
                      str(len(p.contact_points)), p.contact_source or "-", f"{motion:.3f}",
                      "-" if p.shape_error is None else f"{p.shape_error:.3f}")  # fmt: skip
    return table


@common.run_guarded
def run(args: argparse.Namespace) -> int:
    """Run ``mani synthesize``."""
    from manifoundation.sdk import result_figure, result_to_dict, result_to_json
    from manifoundation.sdk.extras import require
    from manifoundation.sdk.tracking import job_result

    if args.view is not None:
        require("plotly", "view", "--view")  # before the job runs, not after
    request = build_request(args)
    with common.job_client(args) as client:
        job = client.submit(request)
        try:
            status = wait_with_progress(job, request.options.timeout, show=not args.json)
        except KeyboardInterrupt:
            job.cancel()
            raise
        if status.state.terminal and status.result is None and status.error is None:
            status = job.status()
        result = job_result(status)
    if args.out is not None:
        result_to_json(result, args.out)
    if args.view is not None:
        fig = result_figure(result, request.object)
        fig.write_html(str(args.view), include_plotlyjs=True, full_html=True)
        if args.open:
            import webbrowser

            webbrowser.open(args.view.resolve().as_uri())
    if args.json:
        common.print_json({"job_id": job.id, "result": result_to_dict(result)})
    else:
        console = common.stdout_console()
        if result.proposals:
            console.print(result_table(result))
        else:
            console.print(f"[yellow]no proposal[/]: the service found no hand pose ({result.hand})")
        timings = ", ".join(f"{k} {v:.3f} s" for k, v in result.timings.items())
        console.print(f"job {job.id}" + (f" · {timings}" if timings else ""))
        for path, what in ((args.out, "result"), (args.view, "3D view")):
            if path is not None:
                console.print(f"{what} written to {path}")
    succeeded = any(p.quality.success for p in result.proposals)
    return common.EXIT_FAILED if args.require_success and not succeeded else common.EXIT_OK
