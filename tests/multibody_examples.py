"""Small textbook mechanisms as description dicts, for the multibody tests."""

from __future__ import annotations

import copy
from pathlib import Path

import numpy as np

MACHINES = Path(__file__).resolve().parents[1] / "src" / "pkmdyn" / "machines"
BUILTIN = ("stewart", "delta", "rrr3", "bennett")

Z = [0.0, 0.0, 1.0]


def body(name, com, mass=1.0, inertia=(0.01, 0.01, 0.01, 0.0, 0.0, 0.0)):
    return {"name": name, "mass_kg": mass, "com_m": list(com), "inertia_kgm2": list(inertia)}


def joint(name, kind, parent, child, point, **kw):
    out = {"name": name, "type": kind, "parent": parent, "child": child, "point_m": list(point)}
    out.update(kw)
    return out


def four_bar():
    """Planar crank-rocker in the plane z = 0.3 (the points of tests/test_mobility.py)."""
    pts = [(0, 0, 0.3), (0.2, 0.9, 0.3), (1.7, 1.4, 0.3), (2.0, 0.0, 0.3)]
    return {
        "mechanism": {"name": "four_bar"},
        "bodies": [body("crank", (0.1, 0.45, 0.3)), body("coupler", (0.95, 1.15, 0.3)), body("rocker", (1.85, 0.7, 0.3))],
        "joints": [joint("A", "revolute", "ground", "crank", pts[0], axis=Z, actuated=True),
                   joint("B", "revolute", "crank", "coupler", pts[1], axis=Z),
                   joint("C", "revolute", "coupler", "rocker", pts[2], axis=Z),
                   joint("D", "revolute", "rocker", "ground", pts[3], axis=Z)],
        "task": {"body": "crank", "euler_sequence": "ZYX", "orientation": [1]},
    }


def slider_crank(slider="prismatic"):
    """Crank 0.1 m, connecting rod 0.35 m, slider along x (a cylindrical joint when asked)."""
    return {
        "mechanism": {"name": "slider_crank"},
        "bodies": [body("crank", (0.0, 0.05, 0.0)), body("rod", (0.165, 0.05, 0.0)), body("slider", (0.33, 0.0, 0.0))],
        "joints": [joint("A", "revolute", "ground", "crank", (0, 0, 0), axis=Z, actuated=True),
                   joint("B", "revolute", "crank", "rod", (0.0, 0.1, 0.0), axis=Z),
                   joint("C", "revolute", "rod", "slider", (0.3354101966249684, 0.0, 0.0), axis=Z),
                   joint("D", slider, "ground", "slider", (0.3354101966249684, 0.0, 0.0), axis=[1.0, 0.0, 0.0])],
        "task": {"body": "crank", "euler_sequence": "ZYX", "orientation": [1]},
    }


def rssr():
    """Spatial RSSR four-bar: one degree of freedom plus the coupler's idle spin."""
    return {
        "mechanism": {"name": "rssr"},
        "bodies": [body("crank", (0.15, 0.05, 0.1)), body("coupler", (0.7, 0.4, 0.35)), body("rocker", (1.25, 0.45, 0.2))],
        "joints": [joint("R1", "revolute", "ground", "crank", (0, 0, 0), axis=[0.2, 0.1, 1.0], actuated=True),
                   joint("S1", "spherical", "crank", "coupler", (0.3, 0.1, 0.2)),
                   joint("S2", "spherical", "coupler", "rocker", (1.1, 0.7, 0.5)),
                   joint("R2", "revolute", "rocker", "ground", (1.4, 0.2, -0.1), axis=[1.0, 0.3, 0.2])],
        "task": {"body": "crank", "euler_sequence": "XYZ", "orientation": [3]},
    }


def builtin_dict(name, parametric=False):
    """A built-in description as a dict: its numbers (the expressions of a parametric file
    evaluated, its [parameters] left out), or with ``parametric`` the file as written."""
    import tomllib

    from pkmdyn.multibody.description.expressions import resolve_parameters

    with open(MACHINES / name / f"{name}.toml", "rb") as fh:
        raw = tomllib.load(fh)
    return raw if parametric else resolve_parameters(raw, name)[0]


def stewart_sps():
    """The built-in Stewart platform with spherical joints on the base: six idle leg spins."""
    d = builtin_dict("stewart")
    for leg in d["legs"]:
        for j in leg["joints"]:
            if j["name"] == "U":
                j["type"] = "spherical"
                j["axis"] = next(k for k in leg["joints"] if k["name"] == "P")["axis"]
                del j["axes"]
    return d


def stewart_with_tool():
    """The built-in Stewart platform with a tool body fixed to the platform; the task on the tool."""
    d = builtin_dict("stewart")
    d["bodies"].append(body("tool", (0.05, 0.0, 1.15), 0.5))
    d["joints"] = [joint("mount", "fixed", "platform", "tool", (0.0, 0.0, 1.1))]
    d["task"] = {"body": "tool", "point_m": [0.1, 0.0, 1.3], "position": ["x", "y", "z"],
                 "euler_sequence": "zyx", "orientation": [1, 2, 3]}
    return d


def rrr3_planar_platform(cut_legs=False):
    """The built-in 3-RRR with a planar joint between platform and ground (redundant)."""
    d = builtin_dict("rrr3")
    d["joints"] = [joint("plane", "planar", "ground", "platform", (0.0, 0.0, 0.0), axis=Z)]
    if cut_legs:
        d["mechanism"]["cut_joints"] = ["RC_1", "RC_2", "RC_3"]
    return d


def deep(d):
    return copy.deepcopy(d)


def smooth_motion(x0, amp, t, seed=0):
    """x0 + amp sin(w t + ph) - amp sin(ph) per coordinate, with exact derivatives."""
    rng = np.random.default_rng(seed)
    k = len(x0)
    w = rng.uniform(2.0, 5.0, k)
    ph = rng.uniform(0, 2 * np.pi, k)
    s, c = np.sin(w * t[:, None] + ph), np.cos(w * t[:, None] + ph)
    return x0 + amp * (s - np.sin(ph)), amp * w * c, -amp * w**2 * s


def four_bar_cut_b():
    """The four-bar cut at B: the tree reaches the rocker and coupler through D and C backwards."""
    d = four_bar()
    d["mechanism"]["cut_joints"] = ["B"]
    return d


def stewart_flipped_spheres():
    """The built-in Stewart platform with every spherical joint described platform -> piston,
    so that the tree traverses one of them backwards (three coordinates, inverse motion)."""
    d = builtin_dict("stewart")
    for leg in d["legs"]:
        for j in leg["joints"]:
            if j["name"] == "S":
                j["parent"], j["child"] = j["child"], j["parent"]
    return d


def sarrus():
    """Sarrus linkage: two chains of three parallel revolutes with crossed axis directions;
    the top moves straight up (Grübler-Kutzbach 0, mobility 1, one over-constraint)."""
    return {
        "mechanism": {"name": "sarrus"},
        "bodies": [body("a1", (0.1, 0, 0.05)), body("a2", (0.1, 0, 0.15)), body("b1", (0, 0.1, 0.05)),
                   body("b2", (0, 0.1, 0.15)), body("top", (0, 0, 0.2))],
        "joints": [joint("A0", "revolute", "ground", "a1", (0.2, 0, 0), axis=[0, 1, 0], actuated=True),
                   joint("A1", "revolute", "a1", "a2", (0.25, 0, 0.1), axis=[0, 1, 0]),
                   joint("A2", "revolute", "a2", "top", (0.2, 0, 0.2), axis=[0, 1, 0]),
                   joint("B0", "revolute", "ground", "b1", (0, 0.2, 0), axis=[1, 0, 0]),
                   joint("B1", "revolute", "b1", "b2", (0, 0.25, 0.1), axis=[1, 0, 0]),
                   joint("B2", "revolute", "b2", "top", (0, 0.2, 0.2), axis=[1, 0, 0])],
        "task": {"body": "top", "position": ["z"], "point_m": [0, 0, 0.2]},
    }


def serial_arm():
    """An open chain (no loop): a planar 2R arm with both joints driven."""
    return {
        "mechanism": {"name": "arm"},
        "bodies": [body("l1", (0.25, 0, 0)), body("l2", (0.75, 0, 0))],
        "joints": [joint("J1", "revolute", "ground", "l1", (0, 0, 0), axis=Z, actuated=True),
                   joint("J2", "revolute", "l1", "l2", (0.5, 0.1, 0), axis=Z, actuated=True)],
        "task": {"body": "l2", "point_m": [0.7, 0.6, 0.0], "position": ["x", "y"]},
    }


def passive_last_drive(d):
    """A redundantly actuated description (a dict, its ``[actuation]`` left out) with its last
    leg copy's drive passive: as many actuated joints as freedoms (the square mechanism whose
    efforts a redundant one's are compared with)."""
    import copy

    d = copy.deepcopy(d)
    d.pop("actuation", None)
    leg = d["legs"][-1]
    if len(leg["angles_deg"]) > 1:  # the last copy split off its leg table
        last = copy.deepcopy(leg)
        n = len(leg["angles_deg"])
        last["angles_deg"] = leg["angles_deg"][-1:]
        last["suffixes"] = [(leg.get("suffixes") or [f"_{k + 1}" for k in range(n)])[-1]]
        leg["angles_deg"] = leg["angles_deg"][:-1]
        if leg.get("suffixes"):
            leg["suffixes"] = leg["suffixes"][:-1]
        d["legs"].append(last)
        leg = last
    for j in leg["joints"]:
        if j.get("actuated"):
            j["actuated"] = False
            j.pop("stiffness", None)
    return d


def round_trip(m0, fmt, folder):
    """``m0`` exported to ``fmt`` (``"mjcf"``, or ``"urdf"`` with its sidecar) in ``folder`` and
    imported back: the description's TOML text."""
    from pkmdyn.io import dumps_yaml
    from pkmdyn.multibody.formats.importer import import_description
    from pkmdyn.multibody.formats.mjcf_out import mechanism_mjcf
    from pkmdyn.multibody.formats.urdf_out import mechanism_urdf

    side = None
    if fmt == "mjcf":
        src = Path(folder) / "m.xml"
        src.write_text(mechanism_mjcf(m0))
    else:
        text, sidecar, _ = mechanism_urdf(m0)
        src, side = Path(folder) / "m.urdf", Path(folder) / "m.yaml"
        src.write_text(text)
        side.write_text(dumps_yaml(sidecar))
    return import_description(src, fmt, sidecar=side)[0]


def mjcf_document(name, worldbody, equality, actuator, option=""):
    """An MJCF model as the import tests write one: angles in radians, ``option`` (a line of
    its own, e.g. a gravity) before the ``worldbody``, then the ``equality`` and ``actuator``
    elements' contents."""
    return (f'<mujoco model="{name}">\n  <compiler angle="radian"/>\n{option}  <worldbody>{worldbody}\n  </worldbody>\n'
            f"  <equality>{equality}\n  </equality>\n  <actuator>{actuator}\n  </actuator>\n</mujoco>\n")
