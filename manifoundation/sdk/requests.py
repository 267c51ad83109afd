"""Whole requests (object + task + robot + options) and robot registrations, validated before sending."""

from __future__ import annotations

import os
import re
from pathlib import Path
from typing import Any

import numpy as np

from manifoundation.contract import ContactsIn, RobotIn, RobotRegister, SynthesisOptions, SynthesisRequest
from manifoundation.sdk.errors import checked
from manifoundation.sdk.objects import ObjectLike, as_object
from manifoundation.sdk.tasks import TaskLike, as_task

RobotLike = RobotIn | str | dict[str, Any]


def as_robot(value: RobotLike) -> RobotIn:
    """Coerce a hand name (``"leap"``), a dict or a `RobotIn` into a `RobotIn`."""
    if isinstance(value, RobotIn):
        return value
    if isinstance(value, str):
        return checked(RobotIn, "robot", name=value)
    return checked(RobotIn, "robot", **value)


def make_request(
    object: ObjectLike | SynthesisRequest,
    task: TaskLike = "force_closure",
    robot: RobotLike | None = "leap",
    *,
    contacts: ContactsIn | dict[str, Any] | None = None,
    **options: Any,
) -> SynthesisRequest:
    """Build and validate a `SynthesisRequest`.

    Args:
        object: anything `as_object` takes: `ObjectIn`, (N, 3)/(N, 6) array, trimesh mesh, file path, dict.
        task: anything `as_task` takes (default: hold the object).
        robot: a hand name, `RobotIn` or dict (default ``"leap"``); None only for a deformable's per-point task
            (contacts and motions for any gripper).
        contacts: given contacts (with ``method="contacts"`` or ``"auto"``).
        **options: `SynthesisOptions` fields: ``method``, ``num_proposals``, ``seed``, ``timeout``, ...

    A `SynthesisRequest` given as ``object`` is returned as it is (the other arguments are ignored).
    """
    if isinstance(object, SynthesisRequest):
        return object
    opts = checked(SynthesisOptions, "options", **options)
    return checked(
        SynthesisRequest,
        "",
        object=as_object(object),
        task=as_task(task),
        robot=None if robot is None else as_robot(robot),
        options=opts,
        contacts=contacts,
    )


def robot_registration(
    urdf: str | bytes | os.PathLike[str],
    fingertips: list[str],
    *,
    name: str | None = None,
    tip_offsets: Any = None,
) -> RobotRegister:
    """Build the body of ``POST /v1/robots`` from URDF text or a ``.urdf`` file.

    Args:
        urdf: the URDF XML (str or bytes) or a path to a ``.urdf`` file.
        fingertips: the fingertip link names, one per finger.
        name: the name to register under (default: the file's stem, else the URDF's ``<robot name>``),
            lower-cased with other characters than ``[a-z0-9_-]`` replaced by ``-``.
        tip_offsets: (len(fingertips), 3) offsets of the contact points in each fingertip link's frame, metres.
    """
    text: str
    if isinstance(urdf, bytes):
        text = urdf.decode("utf-8")
    elif isinstance(urdf, os.PathLike) or (isinstance(urdf, str) and not urdf.lstrip().startswith("<")):
        path = Path(urdf)
        if not path.is_file():
            raise FileNotFoundError(f"urdf: no file {str(path)[:80]!r}; pass URDF text (starting with '<') or a path")
        text = path.read_text(encoding="utf-8")
        name = name or path.stem
    else:
        text = urdf
    if name is None:
        match = re.search(r"<robot[^>]*\bname\s*=\s*[\"']([^\"']+)", text)
        name = match.group(1) if match else "custom-hand"
    clean = re.sub(r"[^a-z0-9_\-]", "-", name.lower()).strip("-_")[:64] or "custom-hand"
    offsets = None if tip_offsets is None else np.asarray(tip_offsets, dtype=np.float64)
    return checked(RobotRegister, "", name=clean, urdf=text, fingertips=list(fingertips), tip_offsets=offsets)
