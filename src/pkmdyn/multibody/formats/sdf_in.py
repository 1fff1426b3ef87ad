"""SDFormat models, read with Python's XML parser, as a :class:`~pkmdyn.multibody.formats.graph.Graph`.

No maintained SDFormat parser installs from PyPI with current numpy (libsdformat's bindings
come with Gazebo; python-sdformat pins numpy < 2), so the few elements a mechanism needs are
read here, following the SDFormat specification (sdformat.org, versions 1.4 to 1.11):

* ``<model>`` (one; inside a ``<world>`` its ``<gravity>``, or SDFormat 1.4's
  ``<physics><gravity>``, else ``0 0 -9.8``, turned into the model frame, which is the base
  frame); nested models, ``<include>``, several models and a static model are refused by name;
* ``<link>``: ``<pose>`` (default relative to the model frame), ``<inertial>`` with its
  ``<pose>`` (relative to the link), ``<mass>`` and ``<inertia>`` (SDFormat's defaults: 1 kg,
  ``ixx = iyy = izz = 1`` kg m^2, also for a link without ``<inertial>``, said in the notes);
* ``<frame>`` (``attached_to``, ``<pose>``) for ``relative_to``;
* ``<joint type>``: ``revolute``, ``continuous``, ``prismatic``, ``ball``, ``universal``
  (``<axis>`` fixed in the parent, ``<axis2>`` in the child), ``fixed``; ``<pose>``
  (default relative to the child link), ``<parent>``, ``<child>`` (``world``: the ground),
  ``<axis><xyz expressed_in>`` (default the joint frame; ``use_parent_model_frame`` of
  SDFormat 1.5-1.6, and every axis of 1.4: the model frame), ``<limit><lower><upper>``,
  ``<dynamics><damping><friction>`` (a one-axis joint in the tree only; elsewhere refused, as
  is a ``spring_stiffness``); ``revolute2``, ``screw``, ``gearbox`` are refused;
* poses ``x y z roll pitch yaw`` (fixed axes, radians; ``degrees="true"``), ``relative_to``.

**Loops.** SDFormat lets a link be the child of several joints: the first joint of each
child (file order) is in the tree, every other one becomes a cut joint of its own type
(pkmdyn's description holds any joint between any two bodies), assembled by construction at
the links' poses. The actuated joints come from ``--actuated`` (SDFormat has no actuators).
"""

from __future__ import annotations

import xml.etree.ElementTree as ET
from pathlib import Path

import numpy as np

from ...errors import ParameterError
from ..description.schema import GROUND
from .graph import Closure, Frame, Graph, Joint, Link, Actuator, safe_name
from .prescan import prescan_sdf

SDF_GRAVITY = (0.0, 0.0, -9.8)


def _floats(text: str | None, n: int, where: str) -> np.ndarray:
    try:
        v = np.array([float(x) for x in (text or "").split()], dtype=float)
    except ValueError:
        v = np.zeros(0)
    if v.shape != (n,) or not np.all(np.isfinite(v)):
        raise ParameterError(f"{where}: {n} finite numbers expected, got {(text or '').strip()[:60]!r}")
    return v


def _rpy(r: float, p: float, y: float) -> np.ndarray:
    from scipy.spatial.transform import Rotation

    return Rotation.from_euler("xyz", [r, p, y]).as_matrix()  # fixed axes: Rz(y) Ry(p) Rx(r)


class _Frames:
    """Poses of the model's frames (links, joints, frames) in the model frame."""

    def __init__(self, model: ET.Element, src: str):
        self.src = src
        self.elem: dict[str, tuple[str, ET.Element]] = {}
        for kind in ("link", "joint", "frame"):
            for e in model.findall(kind):
                nm = e.get("name")
                if not nm:
                    raise ParameterError(f"{src}: a <{kind}> without a name")
                if nm in self.elem:
                    raise ParameterError(f"{src}: {kind} {nm}: a second frame of that name")
                self.elem[nm] = (kind, e)
        self.cache: dict[str, tuple[np.ndarray, np.ndarray]] = {"__model__": (np.eye(3), np.zeros(3)),
                                                                  "world": (np.eye(3), np.zeros(3))}

    def local(self, e: ET.Element, where: str) -> tuple[str | None, np.ndarray, np.ndarray]:
        pe = e.find("pose")
        if pe is None:
            return None, np.eye(3), np.zeros(3)
        if pe.get("rotation_format", "euler_rpy") != "euler_rpy":
            raise ParameterError(f"{where} pose: only rotation_format euler_rpy is read")
        v = _floats(pe.text if (pe.text or "").strip() else "0 0 0 0 0 0", 6, f"{where} pose")  # empty: zero
        if pe.get("degrees", "false").lower() == "true":
            v[3:] = np.radians(v[3:])
        return pe.get("relative_to") or None, _rpy(*v[3:]), v[:3]

    def _step(self, name: str) -> tuple[str, np.ndarray, np.ndarray]:
        """The frame ``name``'s pose relative to the frame it names (``relative_to`` or its default)."""
        if name not in self.elem:
            raise ParameterError(f"{self.src}: frame {name!r}: no link, joint or frame of that name")
        kind, e = self.elem[name]
        rel, R, p = self.local(e, f"{self.src}: {kind} {name}")
        if rel is None:
            rel = {"link": "__model__", "joint": (e.findtext("child") or "").strip(),
                   "frame": e.get("attached_to") or "__model__"}[kind]
        return rel, R, p

    def pose(self, name: str) -> tuple[np.ndarray, np.ndarray]:
        """The frame's pose in the model frame, its chain of ``relative_to`` walked by a loop (a
        chain as long as the file's is no recursion), a cycle refused."""
        chain: list[tuple[str, np.ndarray, np.ndarray]] = []
        busy: set[str] = set()
        cur = name
        while cur not in self.cache:
            if cur in busy:
                raise ParameterError(f"{self.src}: frame {cur}: its pose refers to itself (a cycle of relative_to)")
            busy.add(cur)
            rel, R, p = self._step(cur)
            chain.append((cur, R, p))
            cur = rel
        Rr, pr = self.cache[cur]
        for nm, R, p in reversed(chain):
            Rr, pr = Rr @ R, pr + Rr @ p
            self.cache[nm] = (Rr, pr)
        return self.cache[name]


def sdf_graph(path: str | Path, actuated: tuple[str, ...] = (), assemble: bool = False) -> Graph:
    """The mechanism of an SDFormat file (module docstring)."""
    src = Path(path).name
    if assemble:
        raise ParameterError("--assemble: an SDFormat model is assembled at its links' poses by construction")
    root = prescan_sdf(Path(path), src)
    if root.tag != "sdf":
        raise ParameterError(f"{src}: the root element is <{root.tag}>, not <sdf>")
    world = root.find("world")
    models = (world if world is not None else root).findall("model")
    if not models:
        raise ParameterError(f"{src}: no <model>")
    if len(models) > 1:
        raise ParameterError(f"{src}: model {models[1].get('name')}: more than one <model>; import one mechanism")
    model = models[0]
    if (model.findtext("static") or "").strip().lower() in ("true", "1"):
        raise ParameterError(f"{src}: model {model.get('name')}: a static model does not move")
    try:
        version = tuple(int(x) for x in (root.get("version") or "1.11").split(".")[:2])
    except ValueError:
        raise ParameterError(f"{src}: sdf version {root.get('version')!r} is not a version number") from None
    for bad in ("model", "include"):
        e = model.find(bad)
        if e is not None:
            raise ParameterError(f"{src}: model {model.get('name')}: a nested <{bad}> {e.get('name') or ''} "
                                 "is not read (flatten the model)")
    gravity = np.array(SDF_GRAVITY)
    if world is not None:
        g_text = world.findtext("gravity")
        if g_text is None and world.find("physics") is not None:  # SDFormat 1.4 keeps it under <physics>
            g_text = world.find("physics").findtext("gravity")
        if g_text is not None:
            gravity = _floats(g_text, 3, f"{src}: world gravity")
    fr = _Frames(model, src)
    notes: list[str] = []
    # the base frame is the model frame: the world (and its gravity) as seen from it
    _, Rm, pm = fr.local(model, f"{src}: model {model.get('name')}")
    fr.cache["world"] = (Rm.T, -Rm.T @ pm)
    gravity = Rm.T @ gravity
    links, frames = [], []
    def link_name(raw: str) -> str:
        nm = safe_name(raw, "link")
        return nm if nm != GROUND else "ground_body"  # a moving link called ground is not the base

    for e in model.findall("link"):
        nm = link_name(e.get("name"))
        R, p = fr.pose(e.get("name"))
        # SDFormat's defaults: an <inertial> (or none) without <mass> is 1 kg, ixx = iyy = izz = 1 kg m^2
        ine = e.find("inertial")
        if ine is None:
            ine = ET.Element("inertial")
            notes.append(f"link {nm}: no <inertial>: SDFormat's default, 1 kg and 1 kg m^2")
        where = f"{src}: link {nm} inertial"
        mass = float(_floats(ine.findtext("mass", "1"), 1, f"{where} mass")[0])
        rel, Ri, pi = fr.local(ine, where)
        Rb, pb = fr.pose(rel) if rel else (R, p)  # default: relative to the link
        ie = ine.find("inertia")
        defaults = {"ixx": "1", "iyy": "1", "izz": "1", "ixy": "0", "ixz": "0", "iyz": "0"}
        vals = {k: float(_floats(ie.findtext(k, d) if ie is not None else d, 1, f"{where} {k}")[0])
                for k, d in defaults.items()}
        Il = np.array([[vals["ixx"], vals["ixy"], vals["ixz"]], [vals["ixy"], vals["iyy"], vals["iyz"]],
                       [vals["ixz"], vals["iyz"], vals["izz"]]])
        Rw = Rb @ Ri
        com, I = pb + Rb @ pi, Rw @ Il @ Rw.T
        links.append(Link(nm, mass, com, I))
        frames.append(Frame(nm, nm, p))
    link_names = {e.get("name") for e in model.findall("link")}
    joints, closures, seen_child = [], [], set()
    for e in model.findall("joint"):
        raw = e.get("name")
        nm, typ = safe_name(raw, "joint"), e.get("type", "")
        where = f"{src}: joint {nm}"
        par, ch = (e.findtext("parent") or "").strip(), (e.findtext("child") or "").strip()
        for end, val in (("parent", par), ("child", ch)):
            if val != "world" and val not in link_names:
                raise ParameterError(f"{where} {end}: no link {val!r}")
        if ch == "world":
            raise ParameterError(f"{where}: the world as a child")
        if typ not in ("revolute", "continuous", "prismatic", "ball", "universal", "fixed"):
            raise ParameterError(f"{where}: a {typ or 'untyped'} joint has no equivalent in a description")
        par_l = GROUND if par == "world" else link_name(par)
        ch_l = link_name(ch)
        R, p = fr.pose(raw)
        axes = []
        for tag in ("axis", "axis2"):
            ae = e.find(tag)
            if ae is None:
                axes.append(None)
                continue
            xe = ae.find("xyz")
            a = _floats(xe.text if xe is not None else "0 0 1", 3, f"{where} {tag} xyz")
            exp = xe.get("expressed_in") if xe is not None else None
            if (ae.findtext("use_parent_model_frame") or "").strip().lower() in ("true", "1") or version < (1, 5):
                exp = "__model__"  # SDFormat 1.4: axes in the model frame
            Rx = fr.pose(exp)[0] if exp else R
            axes.append(Rx @ a)
        ax = axes[0]
        lim = None
        dyn = {"damping": 0.0, "frictionloss": 0.0}
        if e.find("axis") is not None:
            le = e.find("axis").find("limit")
            if le is not None and le.find("lower") is not None and le.find("upper") is not None:
                lo, hi = (float(_floats(le.findtext(k), 1, f"{where} limit {k}")[0]) for k in ("lower", "upper"))
                lim = (lo, hi) if lo < hi and max(abs(lo), abs(hi)) < 1e15 else None
        for tag in ("axis", "axis2"):
            ae = e.find(tag)
            de = ae.find("dynamics") if ae is not None else None
            if de is None:
                continue
            if float(_floats(de.findtext("spring_stiffness", "0"), 1, f"{where} spring_stiffness")[0]):
                raise ParameterError(f"{where}: a joint spring (spring_stiffness) has no equivalent in a "
                                     "description's dynamics")
            d = {"damping": float(_floats(de.findtext("damping", "0"), 1, f"{where} damping")[0]),
                 "frictionloss": float(_floats(de.findtext("friction", "0"), 1, f"{where} friction")[0])}
            if any(d.values()) and (tag == "axis2" or typ not in ("revolute", "continuous", "prismatic")
                                    or ch_l in seen_child):
                raise ParameterError(f"{where}: damping or friction on a {typ} joint "
                                     f"{'that closes a loop ' if ch_l in seen_child else ''}has no equivalent")
            dyn = d
        if typ in ("revolute", "continuous", "prismatic", "universal") and ax is None:
            raise ParameterError(f"{where}: a {typ} joint without <axis>")
        if typ == "universal" and axes[1] is None:
            raise ParameterError(f"{where}: a universal joint without <axis2>")
        if lim is not None and (typ == "universal" or ch_l in seen_child):
            notes.append(f"joint {nm}: its limits are not kept (a universal joint or a cut joint has none)")
        if ch_l in seen_child:  # a second parent: a cut joint of this joint's own type
            entry = {"type": {"revolute": "revolute", "continuous": "revolute", "prismatic": "prismatic",
                              "ball": "spherical", "universal": "universal", "fixed": "fixed"}[typ]}
            if typ in ("revolute", "continuous", "prismatic"):
                entry["axis"] = list(map(float, ax))
            elif typ == "universal":
                entry["axes"] = [list(map(float, ax)), list(map(float, axes[1]))]
            closures.append(Closure(nm, "joint", par_l, ch_l, p, p, R, R, joint=entry))
            continue
        seen_child.add(ch_l)
        if typ == "universal":
            mid = f"{ch_l}__u"
            links.append(Link(mid, 0.0, p.copy(), np.zeros((3, 3))))
            joints += [Joint(f"{nm}_1", "hinge", par_l, mid, p, ax), Joint(f"{nm}_2", "hinge", mid, ch_l, p, axes[1])]
        elif typ == "ball":
            joints.append(Joint(nm, "ball", par_l, ch_l, p, np.array([0, 0, 1.0])))
        elif typ == "fixed":
            joints.append(Joint(nm, "fixed", par_l, ch_l, p, np.array([0, 0, 1.0])))
        else:
            joints.append(Joint(nm, "slide" if typ == "prismatic" else "hinge", par_l, ch_l, p, ax,
                                limits=lim if typ != "continuous" else None, **dyn))
    names = {j.name for j in joints} | {c.name for c in closures}
    acts = [safe_name(a, "joint") for a in actuated]
    for a, raw in zip(acts, actuated):
        if a not in names:
            raise ParameterError(f"{src}: actuated joint {raw!r}: no joint of that name")
    return Graph(name=model.get("name") or Path(path).stem, source=src, gravity=gravity, links=links,
                 joints=joints, closures=closures, actuators=[Actuator(a, a) for a in dict.fromkeys(acts)],
                 frames=frames, notes=notes)
