"""Slide tracks, cross-shear and Archard wear of a spherical joint (a joint prosthesis's head in its
cup, or any described mechanism's ball joint), from the two bodies' rotations along a motion
(``docs/wear.md``).

**Markers.** A grid of points fixed on the sphere of one body (the *marker* body: the head for
tracks on the cup), radius ``r``, about a pole direction (default: the joint frame's z axis):
rings at polar angles ``theta_k = k s`` (``s`` the spacing, up to the cap angle), ring ``k > 0``
holding ``max(1, round(2 pi sin(theta_k) / s))`` markers evenly in azimuth (the first at azimuth
0, the joint frame's x), each weighted by the area of its share of the band
``theta_k +- s/2`` (the pole: the cap ``theta <= s/2``; the last band ends at the cap angle);
azimuth 0 along ``normalize(h x pole)``, ``h`` the base axis least aligned with the pole.

**Tracks.** The marker body's rotation relative to the *surface* body, ``R_rel = R_s^T R_m``,
carries each marker over the surface: its track is ``r R_rel(t) m`` (surface frame, from the
centre), shown in the base frame at the reference configuration (``R_s0 R_rel m``). The tracks
of the cup's markers on the head are those of the inverse relative rotation.

- **Sliding distance** ``s = sum r angle(u_i, u_i+1)`` (great-circle arcs between samples) [m];
  speed ``ds/dt``.
- **Track coordinates**: geographic coordinates about the motion's principal axis (the axis of
  most angular-velocity energy of the relative rotation, :func:`motion_axis`: a gait cycle's
  flexion-extension axis): longitude times the cosine of the track's mean latitude, and
  latitude (:func:`geographic`), so that a marker turned about that axis alone draws a straight
  segment whatever its distance from the axis.
- **Aspect ratio** (Saikko et al. 2004): the ratio of the track's extents (max - min) along the
  principal axes (sample covariance) of its track coordinates; ``1e9`` where the minor extent
  vanishes (a straight track), ``1`` for a marker that does not move.
- **Cross-shear** (the frictional-work form of Wang 2001 and Kang et al. 2008): each sliding
  increment's frictional work ``dW = mu L ds`` (``L`` the load through the joint, ``mu`` constant,
  so it cancels) split between the principal molecular orientation (PMO) and its normal by the
  increment's direction ``e`` in the track coordinates: with ``T = sum dW e e^T`` the PMO is
  ``T``'s principal eigenvector and ``CS = lambda_min / (lambda_min + lambda_max)`` (the work
  across the PMO over the whole work): 0 for a straight track, 1/2 for a circle.
- **Track integral of load** (Calonius and Saikko 2002) ``I = sum L ds`` [N m], ``L`` the mean
  of the two samples' loads.
- **Wear** (Archard): per marker ``V = k f(CS) I`` [mm^3 per cycle, ``k`` in mm^3/(N m)], ``f`` the
  user's cross-shear law (1 when not given); the joint's wear per million cycles is the
  area-weighted mean of the markers' ``V`` (the sliding distance averaged over the contact
  region) times 1e6 / the motion's cycles.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import NDArray

from ...errors import LimitError, ParameterError
from ..description.expressions import evaluate
from ..description.joint_types import JOINT_TYPES
from ..dynamics.newton_euler import joint_reactions
from .stiffness import reaction_route

__all__ = ["WearOptions", "joint_wear", "head_radius", "MarkerGrid", "marker_grid", "marker_count", "SlideTracks", "slide_tracks", "joint_slide_tracks", "motion_axis",
           "geographic", "pole_rotation", "joint_index", "ASPECT_CAP",
           "WEAR_FACTOR_MM3_N_M", "ASPECT_LIMIT"]

Array = NDArray[np.float64]

#: the aspect ratio reported for a straight track (its minor extent below 1e-9 of its major)
ASPECT_CAP = 1e9
#: the default wear factor [mm^3/(N m)]: UHMWPE against a ceramic head in a joint-wear simulator
#: (Saikko 1994, 8e-8 mm^3/(N m)); published values span about 1e-8 to 3e-6 (docs/wear.md)
WEAR_FACTOR_MM3_N_M = 8e-8
#: Saikko et al. (2004): polyethylene wear is realistic only for tracks below this aspect ratio
ASPECT_LIMIT = 5.5


@dataclass(frozen=True)
class MarkerGrid:
    """Unit directions ``u (m, 3)`` about the pole ``(0, 0, 1)``, their polar angle ``theta (m,)``
    [rad] and area weights ``w (m,)`` (summing to the cap's area on the unit sphere)."""

    u: Array
    theta: Array
    w: Array


def _check_grid(spacing_deg: float, cap_deg: float) -> None:
    if not (math.isfinite(spacing_deg) and 0.0 < spacing_deg <= 90.0):
        raise ParameterError(f"marker spacing: {spacing_deg!r} deg is not in (0, 90]")
    if not (math.isfinite(cap_deg) and 0.0 < cap_deg <= 180.0):
        raise ParameterError(f"marker cap: {cap_deg!r} deg is not in (0, 180] (a cap of 0 holds the pole's "
                             "marker alone)")


def marker_count(spacing_deg: float = 10.0, cap_deg: float = 60.0) -> int:
    """The markers of :func:`marker_grid` counted without building it: exact up to 10^8 markers,
    above that the cap's area over the spacing squared (a lower estimate; too many either way)."""
    _check_grid(spacing_deg, cap_deg)
    s, cap = math.radians(spacing_deg), math.radians(cap_deg)
    estimate = 2.0 * math.pi * (1.0 - math.cos(cap)) / (s * s) if s * s > 0 else math.inf
    if estimate > 1e8:
        return int(min(estimate, 1e18))
    k = np.arange(1, int(math.floor((cap + 1e-12) / s)) + 1)
    k = k[k * s <= cap + 1e-12]
    return 1 + int(np.maximum(1, np.round(2 * np.pi * np.sin(k * s) / s)).sum())


def marker_grid(spacing_deg: float = 10.0, cap_deg: float = 60.0, max_markers: int | None = 1_000_000) -> MarkerGrid:
    """The marker grid (module docstring) about the +z pole; refused (before anything is built)
    where it would hold more than ``max_markers`` markers."""
    _check_grid(spacing_deg, cap_deg)
    if max_markers is not None:
        n = marker_count(spacing_deg, cap_deg)
        if n > max_markers:
            raise LimitError(f"marker grid: {n:,} markers at a spacing of {spacing_deg:g} deg over a cap of "
                             f"{cap_deg:g} deg exceed the {max_markers:,} allowed (widen --spacing-deg)")
    s, cap = math.radians(spacing_deg), math.radians(cap_deg)
    u, th, w = [], [], []
    k = 0
    while k * s <= cap + 1e-12:
        t = k * s
        last = (k + 1) * s > cap + 1e-12  # the last ring's band runs to the cap
        lo, hi = max(0.0, t - s / 2), cap if last else min(cap, t + s / 2)
        band = 2 * math.pi * (math.cos(lo) - math.cos(hi)) if hi > lo else 0.0
        count = 1 if k == 0 else max(1, round(2 * math.pi * math.sin(t) / s))
        for j in range(count):
            phi = 2 * math.pi * j / count
            u.append((math.sin(t) * math.cos(phi), math.sin(t) * math.sin(phi), math.cos(t)))
            th.append(t)
            w.append(band / count)
        k += 1
    w_arr = np.array(w)
    if not w_arr.sum() > 0:  # a zero cap: the pole alone
        w_arr = np.ones_like(w_arr)
    return MarkerGrid(u=np.array(u), theta=np.array(th), w=w_arr)


@dataclass(frozen=True)
class SlideTracks:
    """Slide tracks of ``m`` markers over ``n`` samples (module docstring), SI unless named.

    ``points (n, m, 3)`` [m] the tracks on the surface body (from the sphere's centre, base frame
    at the reference configuration); ``markers (m, 3)`` the markers' unit directions on their own
    body at the reference configuration (base frame) and ``pole`` (3,) the grid's axis there;
    ``weights (m,)``; ``sliding_distance (m,)`` [m]; ``mean_speed``, ``peak_speed``
    (m,) [m/s]; ``aspect_ratio (m,)``; ``major_extent``, ``minor_extent`` (m,) [m];
    ``cross_shear (m,)``; ``load_integral (m,)`` [N m]; ``wear (m,)`` [mm^3 over the motion];
    ``wear_per_million_cycles`` [mm^3]; ``cycles`` the motion's cycles."""

    points: Array
    markers: Array
    pole: Array
    weights: Array
    sliding_distance: Array
    mean_speed: Array
    peak_speed: Array
    aspect_ratio: Array
    major_extent: Array
    minor_extent: Array
    cross_shear: Array
    load_integral: Array
    wear: Array
    wear_per_million_cycles: float
    cycles: float

    def columns(self) -> dict[str, Array]:
        """The markers' table ``pkmdyn wear`` writes for these tracks
        (``markers_<joint>_on_<surface>.csv``, docs/wear.md), one row per marker, by column name."""
        return {"marker": np.arange(len(self.weights), dtype=float),
                **{f"direction_{c}": self.markers[:, k] for k, c in enumerate("xyz")},
                "weight": self.weights, "sliding_distance_per_cycle_m": self.sliding_distance / self.cycles,
                "aspect_ratio": self.aspect_ratio, "cross_shear": self.cross_shear,
                "track_load_integral_per_cycle_N_m": self.load_integral / self.cycles,
                "wear_mm3_per_million_cycles": self.wear * 1e6 / self.cycles}

    def summary(self) -> dict:
        """Statistics over the markers (``docs/wear.md``, ``wear.json``)."""
        ar, cs, sd = self.aspect_ratio, self.cross_shear, self.sliding_distance

        def stats(v: Array) -> dict:
            return {"min": float(v.min()), "mean": float(v.mean()), "median": float(np.median(v)),
                    "max": float(v.max())}

        return {
            "markers": int(len(ar)),
            "sliding_distance_per_cycle_m": stats(sd / self.cycles),
            "mean_sliding_speed_m_s": stats(self.mean_speed),
            "aspect_ratio": stats(ar),
            "share_aspect_ratio_above_5_5": float(np.mean(ar > ASPECT_LIMIT)),  # of the markers
            "area_share_aspect_ratio_above_5_5": float(self.weights[ar > ASPECT_LIMIT].sum() / self.weights.sum()),
            "cross_shear": stats(cs),
            "track_load_integral_per_cycle_N_m": stats(self.load_integral / self.cycles),
            "wear_volume_mm3_per_million_cycles": float(self.wear_per_million_cycles),
        }


def _arcs(u: Array) -> Array:
    """Great-circle angles (n - 1, m) between consecutive unit points ``u (n, m, 3)``."""
    a, b = u[:-1], u[1:]
    return np.arctan2(np.linalg.norm(np.cross(a, b), axis=-1), np.einsum("nmi,nmi->nm", a, b))


def motion_axis(R_rel: Array, t: Array) -> Array:
    """The relative rotation's principal axis (3,) (surface frame): the principal eigenvector of
    ``sum v v^T / dt`` over the samples' rotation increments ``v`` (rotation vectors of
    ``R_rel(t_i+1) R_rel(t_i)^T``), the axis of most angular-velocity energy (a gait cycle's
    flexion-extension axis)."""
    from scipy.spatial.transform import Rotation

    dR = np.einsum("nij,nkj->nik", R_rel[1:], R_rel[:-1])
    v = Rotation.from_matrix(dR).as_rotvec()
    S = np.einsum("ni,nj,n->ij", v, v, 1.0 / np.diff(t))
    lam, vec = np.linalg.eigh(S)
    axis = vec[:, -1] if lam[-1] > 0 else np.array([1.0, 0.0, 0.0])
    return axis * (1.0 if axis[np.argmax(np.abs(axis))] > 0 else -1.0)


def geographic(u: Array, axis: Array) -> Array:
    """Each track's planar coordinates (n, m, 2) [rad]: longitude about ``axis`` (unwrapped along
    the motion) times the cosine of the track's mean latitude, and latitude, each from its mean
    over the track (module docstring)."""
    B = pole_rotation(axis)
    e1, e2 = B[:, 0], B[:, 1]
    lat = np.arcsin(np.clip(u @ axis, -1.0, 1.0))
    lon = np.unwrap(np.arctan2(u @ e2, u @ e1), axis=0)
    lat0 = lat.mean(axis=0)
    return np.stack([(lon - lon.mean(axis=0)) * np.cos(lat0), lat - lat0], axis=-1)


def _shape(a: Array, arcs: Array, load: Array) -> tuple[Array, Array, Array, Array]:
    """Aspect ratio, major and minor extent [rad] and cross-shear of each track from its planar
    coordinates ``a (n, m, 2)`` (:func:`geographic`)."""
    d = a - a.mean(axis=0)
    cov = np.einsum("nmi,nmj->mij", d, d)
    _, vec = np.linalg.eigh(cov)
    pa = np.einsum("nmi,mi->nm", a, vec[:, :, 1])
    pb = np.einsum("nmi,mi->nm", a, vec[:, :, 0])
    ext1, ext2 = pa.max(axis=0) - pa.min(axis=0), pb.max(axis=0) - pb.min(axis=0)
    big, small = np.maximum(ext1, ext2), np.minimum(ext1, ext2)
    aspect = np.where(small > big / ASPECT_CAP, big / np.maximum(small, 1e-300), ASPECT_CAP)
    aspect = np.where(big > 1e-12, aspect, 1.0)
    # cross-shear: the increments' directions in the plane, weighted by their work
    da = a[1:] - a[:-1]
    ln = np.linalg.norm(da, axis=-1)
    e = da / np.maximum(ln, 1e-300)[..., None]
    dW = 0.5 * (load[1:] + load[:-1])[:, None] * arcs
    T = np.einsum("nm,nmi,nmj->mij", dW * (ln > 0), e, e)
    lam = np.linalg.eigvalsh(T)
    tot = lam.sum(axis=1)
    cs = np.where(tot > 0, np.maximum(lam[:, 0], 0.0) / np.where(tot > 0, tot, 1.0), 0.0)
    return aspect, big, small, cs


def slide_tracks(R_rel: Array, t: Array, load: Array, radius_m: float, grid: MarkerGrid | None = None,
                 pole: Array | None = None, frame: Array | None = None, marker_frame: Array | None = None,
                 cycles: float = 1.0,
                 wear_factor_mm3_N_m: float = WEAR_FACTOR_MM3_N_M, cross_shear_law: str | None = None) -> SlideTracks:
    """Slide tracks of the markers (``grid`` about ``pole``, unit, in the marker body's frame;
    default +z) under the marker body's rotation relative to the surface body ``R_rel (n, 3,
    3)`` at times ``t (n,)`` [s] with the load through the joint ``load (n,)`` [N]; ``frame``,
    ``marker_frame`` (3, 3): the surface and the marker body's frames in the base frame at the
    reference configuration (the points' and the markers' axes; identity by default); ``cycles``: the cycles the motion spans;
    ``cross_shear_law``: an expression of ``cs`` (docs/mechanism_format.md, "Parameters"
    grammar) scaling each marker's wear."""
    R_rel = np.asarray(R_rel, dtype=float)
    t = np.asarray(t, dtype=float)
    load = np.abs(np.asarray(load, dtype=float))
    n = R_rel.shape[0]
    if n < 2 or t.shape != (n,) or load.shape != (n,):
        raise ParameterError("slide tracks: need at least two samples, with a time and a load each")
    if not (math.isfinite(radius_m) and radius_m > 0):
        raise ParameterError(f"head radius: {radius_m!r} m is not a positive length")
    if not (math.isfinite(wear_factor_mm3_N_m) and wear_factor_mm3_N_m > 0):
        raise ParameterError(f"wear factor: {wear_factor_mm3_N_m!r} mm^3/(N m) is not positive")
    if not (math.isfinite(cycles) and cycles > 0):
        raise ParameterError(f"cycles: {cycles!r} is not positive")
    grid = marker_grid() if grid is None else grid
    if len(grid.u) == 0:
        raise ParameterError("marker grid: no marker")
    P = pole_rotation(np.array([0.0, 0.0, 1.0]) if pole is None else np.asarray(pole, dtype=float))
    m0 = grid.u @ P.T  # marker directions in the marker body's frame
    F = np.eye(3) if frame is None else np.asarray(frame, dtype=float)
    u = np.einsum("ij,njk,mk->nmi", F, R_rel, m0)
    arcs = _arcs(u)
    ds = radius_m * arcs
    dt = np.diff(t)
    if np.any(dt <= 0):
        raise ParameterError("slide tracks: the times must increase")
    sliding = ds.sum(axis=0)
    speed = ds / dt[:, None]
    axis = motion_axis(R_rel, t)
    aspect, big, small, cs = _shape(geographic(np.einsum("ij,nmj->nmi", F.T, u), axis), arcs, load)
    integral = (0.5 * (load[1:] + load[:-1])[:, None] * ds).sum(axis=0)
    factor = _law(cross_shear_law, cs)
    wear = wear_factor_mm3_N_m * factor * integral
    per_million = float(np.sum(grid.w * wear) / np.sum(grid.w)) * 1e6 / cycles
    Fm = np.eye(3) if marker_frame is None else np.asarray(marker_frame, dtype=float)
    return SlideTracks(points=radius_m * u, markers=m0 @ Fm.T, pole=Fm @ P[:, 2], weights=grid.w, sliding_distance=sliding,
                       mean_speed=sliding / (t[-1] - t[0]), peak_speed=speed.max(axis=0), aspect_ratio=aspect,
                       major_extent=radius_m * big, minor_extent=radius_m * small, cross_shear=cs,
                       load_integral=integral, wear=wear, wear_per_million_cycles=per_million, cycles=float(cycles))


def pole_rotation(pole: Array) -> Array:
    """A rotation taking +z to the unit ``pole`` (the marker grid's axis; the track coordinates'
    and the pictures' axes): x along ``normalize(h x pole)``, ``h`` the base axis least aligned
    with the pole."""
    nrm = float(np.linalg.norm(pole))
    if not (math.isfinite(nrm) and nrm > 0):
        raise ParameterError(f"pole: {pole.tolist()!r} is not a direction")
    z = pole / nrm
    h = np.zeros(3)
    h[int(np.argmin(np.abs(z)))] = 1.0
    x = np.cross(h, z)
    x /= np.linalg.norm(x)
    return np.stack([x, np.cross(z, x), z], axis=1)


def _law(text: str | None, cs: Array) -> Array:
    """The cross-shear law ``f(cs)`` per marker (1 without one); positive and finite."""
    if text is None:
        return np.ones_like(cs)
    out = np.array([float(evaluate(text, {"cs": float(c)}, "--cross-shear-law")) for c in cs])
    if not np.all(np.isfinite(out)) or np.any(out < 0):
        raise ParameterError(f"--cross-shear-law {text!r}: gives a negative or non-finite factor")
    return out


def joint_index(model, joint: str) -> int:
    """The index of the joint named ``joint``; one line naming it when the model has none."""
    names = list(model.joint_names)
    if joint not in names:
        raise ParameterError(f"--joint {joint!r}: not a joint of {model.name} ({', '.join(names[:12])}"
                             f"{' ...' if len(names) > 12 else ''})")
    return names.index(joint)


def joint_slide_tracks(model, kin, joint: str, load: Array, radius_m: float, head: str = "child",
                       on: str = "cup", **kw) -> SlideTracks:
    """:func:`slide_tracks` of the spherical joint ``joint`` of a described mechanism along the
    kinematics ``kin``: the head is the joint's ``child`` (or ``parent``) body, the cup the other;
    ``on = "cup"`` the head's markers on the cup, ``"head"`` the cup's markers on the head. The
    pole defaults to the joint frame's z axis (base frame at the reference configuration)."""
    j = joint_index(model, joint)

    jt = JOINT_TYPES[model.joint_type[j]]
    if jt.name != "spherical":
        raise ParameterError(f"joint {joint!r} is a {jt.name} joint: slide tracks need a spherical joint")
    if head not in ("child", "parent") or on not in ("cup", "head"):
        raise ParameterError("head: 'child' or 'parent'; on: 'cup' or 'head'")
    bc, bp = int(model.joint_child[j]), int(model.joint_parent[j])
    n = len(kin)
    eye = np.broadcast_to(np.eye(3), (n, 3, 3))
    R_c = kin.R[:, bc] if bc >= 0 else eye
    R_p = kin.R[:, bp] if bp >= 0 else eye
    R_head, R_cup = (R_c, R_p) if head == "child" else (R_p, R_c)
    b_head, b_cup = (bc, bp) if head == "child" else (bp, bc)
    R0 = {b: (model.R0[b] if b >= 0 else np.eye(3)) for b in (bc, bp)}
    if on == "cup":
        R_rel, marker_body, surface_body = np.einsum("nji,njk->nik", R_cup, R_head), b_head, b_cup
    else:
        R_rel, marker_body, surface_body = np.einsum("nji,njk->nik", R_head, R_cup), b_cup, b_head
    # the pole (base frame at the reference configuration) in the marker body's frame
    pole = kw.pop("pole", None)
    if pole is None:
        pole = model.joint_R_parent[j][:, 2] if model.joint_parent[j] < 0 else model.R0[bp] @ model.joint_R_parent[j][:, 2]
    pole_body = R0[marker_body].T @ np.asarray(pole, dtype=float)
    return slide_tracks(R_rel, kin.t if kin.t is not None else np.arange(n, dtype=float), load, radius_m,
                        pole=pole_body, frame=R0[surface_body], marker_frame=R0[marker_body], **kw)


@dataclass(frozen=True)
class WearOptions:
    """The wear analysis's settings (``docs/wear.md``): ``radius_m`` (None: the joint's
    friction ``ball_radius_m``), ``head`` the body carrying the head (``child`` or ``parent``),
    ``load`` a named load's name (None: the joint's own reaction force), the marker grid's
    ``spacing_deg`` and ``cap_deg``, ``pole`` (None: the joint frame's z axis), the wear factor
    [mm^3/(N m)], an optional cross-shear law of ``cs``, the ``cycles`` the motion spans and the
    most markers the grid may hold (``max_markers``, None: no bound)."""

    radius_m: float | None = None
    head: str = "child"
    load: str | None = None
    spacing_deg: float = 10.0
    cap_deg: float = 60.0
    pole: tuple[float, float, float] | None = None
    wear_factor_mm3_N_m: float = WEAR_FACTOR_MM3_N_M
    cross_shear_law: str | None = None
    cycles: float = 1.0
    max_markers: int | None = 1_000_000


def head_radius(model: Any, joint: str, given: float | None) -> float:
    """The sphere's radius: ``given``, else the joint's friction ``ball_radius_m``; refused by
    name when neither is there."""
    j = joint_index(model, joint)
    if given is not None:
        return float(given)
    fr = model.joint_friction[j] or {}
    r = float(fr.get("ball_radius_m", 0.0) or 0.0)
    if r <= 0:
        raise ParameterError(f"joint {joint!r}: no head radius (give --radius-m, or the joint's friction "
                             "ball_radius_m)")
    return r


def _load(model: Any, kin: Any, joint: str, opts: WearOptions, named: dict) -> tuple[Array, str]:
    """The load through the joint (n,) [N] and its description."""
    if opts.load is not None:
        if opts.load not in named:
            have = ", ".join(sorted(named)) or "none"
            raise ParameterError(f"--load {opts.load!r}: not a named load of the motion ({have})")
        return np.abs(np.asarray(named[opts.load], dtype=float)), f"named load {opts.load}"
    reac = joint_reactions(model, kin, named=named or None, overconstrained=reaction_route(model))
    j = joint_index(model, joint)
    return np.linalg.norm(reac.joint_force[:, j], axis=1), f"the reaction force of joint {joint}"


def joint_wear(model: Any, kin: Any, joint: str, opts: WearOptions, named: dict | None = None
               ) -> tuple[SlideTracks, SlideTracks, str]:
    """The head's markers' tracks on the cup and the cup's markers' tracks on the head of the
    spherical joint ``joint`` along ``kin`` (its loads ``named``), and the load's description."""
    named = dict(named or {})
    r = head_radius(model, joint, opts.radius_m)
    grid = marker_grid(opts.spacing_deg, opts.cap_deg, opts.max_markers)
    load, what = _load(model, kin, joint, opts, named)
    kw = dict(grid=grid, pole=opts.pole, cycles=opts.cycles, wear_factor_mm3_N_m=opts.wear_factor_mm3_N_m,
              cross_shear_law=opts.cross_shear_law)
    on_cup = joint_slide_tracks(model, kin, joint, load, r, head=opts.head, on="cup", **kw)
    on_head = joint_slide_tracks(model, kin, joint, load, r, head=opts.head, on="head", **kw)
    return on_cup, on_head, what
