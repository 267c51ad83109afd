"""An untrusted MJCF from an archive, compiled by MuJoCo with nothing read outside the archive.

MuJoCo opens every file a model names (meshes, textures, included files, plugins), so the document is rewritten
before MuJoCo sees it:

1. parsed with ``defusedxml`` (no DTDs or entities), capped in size;
2. ``<include file>`` elements replaced by the children of the included member (depth ≤ ``MAX_INCLUDE_DEPTH``),
   counted as they are read (``MAX_INCLUDES`` includes, ``MAX_EXPANDED_BYTES`` of included text and
   ``MAX_ELEMENTS`` elements over all documents), so an include bomb is refused before it is inlined;
3. ``<compiler meshdir/assetdir/texturedir>`` applied to each ``<mesh file>`` (relative to the main document's
   folder, as MuJoCo does), the member checked with the mesh caps (:mod:`manifoundation.core.robots.archive_meshes`) and
   the attribute replaced by a flat name ``asset<i>.<ext>`` that MuJoCo finds in the in-memory asset map;
4. textures, skins and height fields dropped (they draw, they do not collide) with materials' texture references,
   and the compiler's folder attributes removed;
5. anything else that names a file or loads code (``<plugin>``, ``<extension>``, ``<model>``, a remaining
   ``file*`` attribute) refused.

MuJoCo then compiles the rewritten string with ``MjModel.from_xml_string(xml, assets)``: every file it asks for
is in ``assets``.
"""

from __future__ import annotations

import posixpath
import xml.etree.ElementTree as ET
from dataclasses import dataclass
from typing import TYPE_CHECKING

from defusedxml import DefusedXmlException
from defusedxml.ElementTree import fromstring

from manifoundation.core.errors import HandLoadError
from manifoundation.core.robots.archive import HandArchive
from manifoundation.core.robots.archive_meshes import ArchiveMeshes
from manifoundation.core.robots.urdf import MAX_URDF_BYTES

if TYPE_CHECKING:
    import mujoco  # untyped (no stubs): its objects read as Any

MAX_MJCF_BYTES = MAX_URDF_BYTES
MAX_INCLUDE_DEPTH = 8
MAX_ELEMENTS = 50_000  # in the main document and every included one, counted as they are read
MAX_INCLUDES = 1_000  # <include> elements resolved, in all
MAX_EXPANDED_BYTES = 4 * MAX_MJCF_BYTES  # text of every included member read, in all
REFUSED_TAGS = ("plugin", "extension", "model", "instance")
DROPPED_TAGS = ("texture", "skin", "hfield")


def _parse(data: bytes, what: str) -> ET.Element:
    if len(data) > MAX_MJCF_BYTES:
        raise HandLoadError(f"{what}: {len(data)} bytes, over the {MAX_MJCF_BYTES}-byte limit")
    try:
        root: ET.Element = fromstring(data, forbid_dtd=True, forbid_entities=True, forbid_external=True)
    except DefusedXmlException as e:
        raise HandLoadError(
            f"{what}: unsafe XML rejected ({type(e).__name__}): DTDs and entities are not allowed"
        ) from e
    except ET.ParseError as e:
        raise HandLoadError(f"{what}: malformed XML: {e}") from e
    if root.tag != "mujoco":
        raise HandLoadError(f"{what}: root element is <{root.tag}>, expected <mujoco>")
    return root


@dataclass
class _Expansion:
    """What inlining has cost so far, over every document read (checked before each member is parsed or inlined)."""

    elements: int = 0
    includes: int = 0
    read_bytes: int = 0

    def add_document(self, root: ET.Element, what: str) -> None:
        self.elements += sum(1 for _ in root.iter())
        if self.elements > MAX_ELEMENTS:
            raise HandLoadError(
                f"MJCF: <include> expansion passes {MAX_ELEMENTS} elements at {what} (limit MAX_ELEMENTS); refused "
                "before inlining"
            )

    def add_include(self, size: int, what: str) -> None:
        self.includes += 1
        self.read_bytes += size
        if self.includes > MAX_INCLUDES:
            raise HandLoadError(f"MJCF: more than {MAX_INCLUDES} <include> elements in all (limit MAX_INCLUDES)")
        if self.read_bytes > MAX_EXPANDED_BYTES:
            raise HandLoadError(
                f"MJCF: <include> of {what} brings the included text to {self.read_bytes} bytes, over the "
                f"{MAX_EXPANDED_BYTES}-byte limit"
            )


def _inline_includes(root: ET.Element, archive: HandArchive, base: str, cost: _Expansion, depth: int = 0) -> None:
    """Replace each ``<include>`` below ``root`` by the children of its (expanded) member, in document order.

    Every member is counted (includes, bytes, elements) before it is parsed or inlined, so a file that includes
    another many times over is refused after at most ``MAX_ELEMENTS`` elements of work, whatever its depth.
    """
    for parent in list(root.iter()):
        children = list(parent)
        if not any(child.tag == "include" for child in children):
            continue
        expanded: list[ET.Element] = []
        for child in children:
            if child.tag != "include":
                expanded.append(child)
                continue
            if depth >= MAX_INCLUDE_DEPTH:
                raise HandLoadError(f"MJCF: <include> nested deeper than {MAX_INCLUDE_DEPTH} (limit MAX_INCLUDE_DEPTH)")
            member = archive.resolve(child.get("file") or "", base)
            data = archive.files[member]
            cost.add_include(len(data), repr(member))
            sub = _parse(data, f"included {member!r}")
            cost.add_document(sub, f"included {member!r}")
            _inline_includes(sub, archive, base, cost, depth + 1)  # MuJoCo resolves every path against the main file
            expanded.extend(sub)
        parent[:] = expanded


def _folders(root: ET.Element) -> tuple[str, str]:
    meshdir = assetdir = ""
    for comp in root.iter("compiler"):
        meshdir = comp.get("meshdir", meshdir)
        assetdir = comp.get("assetdir", assetdir)
        for key in ("meshdir", "assetdir", "texturedir"):
            comp.attrib.pop(key, None)
    return meshdir or assetdir, assetdir


def sanitised_mjcf(archive: HandArchive, member: str, meshes: ArchiveMeshes) -> tuple[str, dict[str, bytes], list[str]]:
    """The rewritten document, its asset map and what was dropped (see module doc).

    Args:
        archive: the checked archive.
        member: the MJCF member to compile.
        meshes: the archive's mesh loader (caps and cache shared with the rest of the load).

    Returns:
        ``(xml, assets, dropped)``: the document MuJoCo compiles, flat asset name → bytes, one line per kind of
        element dropped.

    Raises:
        HandLoadError: unsafe or malformed XML, a missing or oversized member, a refused element.
    """
    base = posixpath.dirname(member)
    root = _parse(archive.files[member], f"MJCF {member!r}")
    cost = _Expansion()
    cost.add_document(root, f"MJCF {member!r}")
    _inline_includes(root, archive, base, cost)
    meshdir, _ = _folders(root)
    dropped: dict[str, int] = {}
    for parent in list(root.iter()):
        for child in list(parent):
            if child.tag in DROPPED_TAGS:
                parent.remove(child)
                dropped[child.tag] = dropped.get(child.tag, 0) + 1
    assets: dict[str, bytes] = {}
    for elem in root.iter():
        if elem.tag in REFUSED_TAGS:
            raise HandLoadError(f"MJCF: <{elem.tag}> is not accepted (it loads code or another model)")
        if elem.tag == "material":
            elem.attrib.pop("texture", None)
        if elem.tag == "mesh" and elem.get("file"):
            name = archive.resolve(elem.get("file") or "", posixpath.join(base, meshdir))
            meshes.mesh(name)  # the caps, before MuJoCo parses it
            flat = f"asset{len(assets)}.{name.rsplit('.', 1)[-1].lower()}"
            assets[flat] = archive.files[name]
            elem.set("file", flat)
        named = [k for k in elem.attrib if k.startswith("file") or k in ("meshdir", "assetdir", "texturedir")]
        leftover = [k for k in named if not (elem.tag == "mesh" and k == "file")]
        if leftover:
            raise HandLoadError(f"MJCF: <{elem.tag} {leftover[0]}=...> names a file that is not a mesh; refused")
    notes = [f"{n} <{tag}> element(s) dropped (drawing only)" for tag, n in sorted(dropped.items())]
    return ET.tostring(root, encoding="unicode"), assets, notes


def compile_mjcf(archive: HandArchive, member: str, meshes: ArchiveMeshes) -> tuple[mujoco.MjModel, list[str]]:
    """``mujoco.MjModel`` of the archive's MJCF ``member`` and the drop notes (see :func:`sanitised_mjcf`).

    Raises:
        HandLoadError: as :func:`sanitised_mjcf`, or MuJoCo's compile error (its message, e.g. a missing mesh).
    """
    import mujoco

    xml, assets, notes = sanitised_mjcf(archive, member, meshes)
    try:
        model = mujoco.MjModel.from_xml_string(xml, assets)
    except ValueError as e:
        raise HandLoadError(f"MJCF {member!r}: MuJoCo could not compile it: {e}") from e
    return model, notes
