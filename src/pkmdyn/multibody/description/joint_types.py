"""The joint-type table: every joint type's kinematics in one place.

A joint joins a frame ``P`` fixed in its parent body to a frame ``C`` fixed in its child body.
Its relative motion ``X_J(q)`` (frame C in frame P) is a product of *elementary motions* in
the joint frame, applied left to right: a rotation about, or a translation along, the current
x, y or z axis (``RX RY RZ TX TY TZ``). The motion subspace of coordinate k is the unit twist
of its elementary motion (Featherstone, *Rigid Body Dynamics Algorithms*, 2008, Table 4.1,
written as a product of single-axis joints).

When the joint is cut to open a loop, it becomes a constraint record: each constrained
relative direction is one scalar residual of the two frames ``P`` (axes ``e_0 e_1 e_2``,
origin ``o_P``) and ``C`` (axes ``c_0 c_1 c_2``, origin ``o_C``), in world coordinates:

* ``("T", i)``: translation along ``e_i``, residual ``e_i . (o_C - o_P)``;
* ``("R", i, j)``: relative rotation, residual ``e_i . c_j`` (zero when aligned).

The rotation rows are the off-diagonal entries of ``R_P^T R_C`` that vanish for every value
of the joint's free coordinates, so the residuals are exact (not linearised) and their
derivatives are exact too. The direction names (``force_x``, ``couple_y``, in the joint
frame P) are the reactions a cut joint of that type carries.

Adding a joint type is adding one :class:`JointType` entry to :data:`JOINT_TYPES`.
"""

from __future__ import annotations

from dataclasses import dataclass

__all__ = ["JointType", "JOINT_TYPES", "MOTION_CODES", "joint_type", "type_code"]

#: elementary motions of the kernels: rotation about x, y, z; translation along x, y, z
MOTION_CODES = {"RX": 0, "RY": 1, "RZ": 2, "TX": 3, "TY": 4, "TZ": 5}

_T = {0: ("T", 0), 1: ("T", 1), 2: ("T", 2)}
_RX, _RY, _RZ = ("R", 1, 2), ("R", 0, 2), ("R", 1, 0)
_NAMES = {("T", 0): "force_x", ("T", 1): "force_y", ("T", 2): "force_z",
          _RX: "couple_x", _RY: "couple_y", _RZ: "couple_z", ("R", 0, 1): "couple_z"}


@dataclass(frozen=True)
class JointType:
    """One joint type.

    ``name``: the description's ``type`` value; ``letter``: the one-letter symbol of the
    mobility literature; ``motions``: elementary motions of its coordinates in order
    (``len(motions)`` = its freedoms); ``constraints``: the residual rows of a cut joint of
    this type (see the module docstring); ``axes``: how many axes the description gives
    (0: none, 1: ``axis`` = the joint frame's z (the normal for planar), 2: ``axes`` = the
    joint frame's x and y, the universal joint's first and second axis); ``units``: the unit
    of each coordinate (``rad`` or ``m``).
    """

    name: str
    letter: str
    motions: tuple[str, ...]
    constraints: tuple[tuple, ...]
    axes: int

    @property
    def freedoms(self) -> int:
        return len(self.motions)

    @property
    def code(self) -> int:
        return type_code(self.name)

    @property
    def units(self) -> tuple[str, ...]:
        return tuple("rad" if m[0] == "R" else "m" for m in self.motions)

    @property
    def directions(self) -> tuple[str, ...]:
        """Names of the constrained directions (reaction components) of a cut joint."""
        return tuple(_NAMES[c] for c in self.constraints)


JOINT_TYPES: tuple[JointType, ...] = (
    JointType("revolute", "R", ("RZ",), (_T[0], _T[1], _T[2], _RX, _RY), 1),
    JointType("prismatic", "P", ("TZ",), (_T[0], _T[1], _RX, _RY, _RZ), 1),
    JointType("cylindrical", "C", ("TZ", "RZ"), (_T[0], _T[1], _RX, _RY), 1),
    # R = Rx(q0) Ry(q1): first axis fixed in the parent, second in the child; x . y stays 0
    JointType("universal", "U", ("RX", "RY"), (_T[0], _T[1], _T[2], ("R", 0, 1)), 2),
    # Rx Ry Rz: singular where the middle angle reaches +-90 deg (choose the joint frame so
    # that it stays far from there; the reference configuration is q = 0)
    JointType("spherical", "S", ("RX", "RY", "RZ"), (_T[0], _T[1], _T[2]), 0),
    JointType("planar", "E", ("TX", "TY", "RZ"), (_T[2], _RX, _RY), 1),
    JointType("fixed", "F", (), (_T[0], _T[1], _T[2], _RX, _RY, _RZ), 0),
)

_BY_NAME = {t.name: k for k, t in enumerate(JOINT_TYPES)}


def type_code(name: str) -> int:
    """Index of joint type ``name`` in :data:`JOINT_TYPES` (the integer the kernels use)."""
    return _BY_NAME[name]


def joint_type(name: str) -> JointType:
    """The table entry of ``name`` (a KeyError for an unknown name; descriptions validate first)."""
    return JOINT_TYPES[_BY_NAME[name]]
