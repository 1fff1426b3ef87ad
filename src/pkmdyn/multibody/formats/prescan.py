"""Bounds on a model file before any parser builds it: regular files of bounded size, element
counts and nesting within the description's limits, MJCF's ``include``s and ``replicate``s
counted out and its asset files regular files, so that a FIFO, a device, a 2 kB file asking
for a million bodies or a chain of 60,000 links is refused in one line instead of hanging the
reader, exhausting memory or crashing a C++ parser.

The XML is read by the standard library's expat parser (it refuses external entities and
bounds entity expansion); the trees are walked with an explicit stack, never by recursion
that a file's depth controls.
"""

from __future__ import annotations

import math
import os
import stat
import xml.etree.ElementTree as ET
from pathlib import Path

from ...errors import ParameterError
from ..description.schema import MAX_BODIES, MAX_JOINTS

__all__ = ["regular_file", "read_xml", "prescan_mjcf", "prescan_urdf", "prescan_sdf", "MAX_XML_BYTES"]

#: the largest model file read (bytes)
MAX_XML_BYTES = 20_000_000
#: the most elements of one model file, and the deepest nesting
MAX_ELEMENTS = 200_000
MAX_DEPTH = 200
#: the most ``include``s an MJCF file may pull in, all told
MAX_INCLUDES = 100


def regular_file(path: Path, what: str) -> None:
    """Refuse ``path`` unless it is a regular file (not a FIFO, a device, a folder) of at most
    :data:`MAX_XML_BYTES`."""
    try:
        st = os.stat(path)
    except OSError as exc:
        raise ParameterError(f"{what}: cannot read it ({exc.strerror or exc})") from None
    if not stat.S_ISREG(st.st_mode):
        raise ParameterError(f"{what}: not a regular file (a FIFO, device or folder is not read)")
    if st.st_size > MAX_XML_BYTES:
        raise ParameterError(f"{what}: {st.st_size:,} bytes, more than the {MAX_XML_BYTES:,} a model file may hold")


def read_xml(path: Path, what: str) -> ET.Element:
    """The XML root of the regular file ``path``, its elements counted and their nesting
    bounded (:data:`MAX_ELEMENTS`, :data:`MAX_DEPTH`) while it is read."""
    regular_file(path, what)
    depth = count = 0
    root = None
    try:
        for event, elem in ET.iterparse(str(path), events=("start", "end")):
            if event == "start":
                depth += 1
                count += 1
                root = elem if root is None else root
                if depth > MAX_DEPTH:
                    raise ParameterError(f"{what}: elements nested more than {MAX_DEPTH} deep")
                if count > MAX_ELEMENTS:
                    raise ParameterError(f"{what}: more than {MAX_ELEMENTS:,} elements")
            else:
                depth -= 1
    except ET.ParseError as exc:
        raise ParameterError(f"{what}: cannot read it as XML: {exc}") from None
    if root is None:
        raise ParameterError(f"{what}: no XML element")
    return root


def prescan_mjcf(path: Path, src: str) -> None:
    """An MJCF file's bodies counted before MuJoCo compiles it: every ``include`` a regular file
    (at most :data:`MAX_INCLUDES`), every ``replicate``'s count multiplied out, at most
    :data:`~pkmdyn.multibody.description.schema.MAX_BODIES` bodies; asset files that exist are
    regular files."""
    root = read_xml(path, src)
    base = path.parent
    comp = root.find("compiler")
    dirs = {k: (comp.get(k) if comp is not None else None) for k in ("meshdir", "texturedir", "assetdir")}
    includes = 0
    bodies = 0.0
    # (element, body multiplier, include depth)
    stack: list[tuple[ET.Element, float, int]] = [(root, 1.0, 0)]
    while stack:
        e, mult, depth = stack.pop()
        tag = e.tag
        if tag == "replicate":
            try:
                n = int(e.get("count", "1"))
            except ValueError:
                raise ParameterError(f"{src}: replicate count {e.get('count')!r} is not an integer") from None
            mult *= max(n, 0)
        elif tag == "body":
            bodies += mult
            if bodies > MAX_BODIES:
                raise ParameterError(f"{src}: more than {MAX_BODIES} bodies (replicates counted out) before MuJoCo "
                                     "compiles it: a description holds at most that many")
        elif tag == "include":
            includes += 1
            if includes > MAX_INCLUDES or depth >= 20:
                raise ParameterError(f"{src}: more than {MAX_INCLUDES} includes, or includes nested 20 deep")
            name = e.get("file") or ""
            inc = base / name
            sub = read_xml(inc, f"{src}: include {name}")
            stack.extend((c, mult, depth + 1) for c in reversed(list(sub)))
            continue
        if "file" in e.attrib and tag in ("mesh", "hfield", "texture", "skin", "model"):
            sub_dir = dirs["meshdir"] if tag in ("mesh", "skin") else dirs["texturedir"] if tag == "texture" else None
            sub_dir = sub_dir or dirs["assetdir"] or ""
            f = base / sub_dir / e.get("file", "")
            if f.exists() and not f.is_dir() and not stat.S_ISREG(os.stat(f).st_mode):
                raise ParameterError(f"{src}: {tag} file {e.get('file')}: not a regular file (a FIFO or device is "
                                     "not read)")
        if not math.isfinite(mult):
            mult = math.inf
        stack.extend((c, mult, depth) for c in reversed(list(e)))


def prescan_urdf(path: Path, src: str) -> ET.Element:
    """A URDF's root, its links and joints counted before its C++ parser builds it (a chain of
    ten thousand links crashes the parser's recursion)."""
    root = read_xml(path, src)
    links, joints = len(root.findall("link")), len(root.findall("joint"))
    if links > MAX_BODIES + 1 or joints > MAX_JOINTS:
        raise ParameterError(f"{src}: {links:,} links and {joints:,} joints; a description holds at most "
                             f"{MAX_BODIES} bodies and {MAX_JOINTS} joints")
    return root


def prescan_sdf(path: Path, src: str) -> ET.Element:
    """An SDFormat file's root, its links, joints and frames counted first."""
    root = read_xml(path, src)
    for model in root.iter("model"):
        links, joints, frames = (len(model.findall(k)) for k in ("link", "joint", "frame"))
        if links > MAX_BODIES + 1 or joints > MAX_JOINTS or frames > MAX_JOINTS:
            raise ParameterError(f"{src}: model {model.get('name')}: {links:,} links, {joints:,} joints and "
                                 f"{frames:,} frames; a description holds at most {MAX_BODIES} bodies and "
                                 f"{MAX_JOINTS} joints (and a model file at most {MAX_JOINTS} frames)")
    return root
