"""The closed loop's sensors and limits of one cycle, compiled (module docstring of
:mod:`._loop`, items 1-3): the kernels that the Python cycle (:func:`._loop.run_span`) and the
compiled cycles (:mod:`._cycles`) both call."""

from __future__ import annotations

import numba
import numpy as np
from numpy.typing import NDArray

Array = NDArray[np.float64]


@numba.njit(cache=True)
def _sense(kr: int, k: int, j: int, first: bool, exact: bool, s_exact: Array, q: Array, qd: Array, div: Array,
           noise: Array, pose_from_sensor: bool, ref: tuple, filt: tuple, mem: tuple,
           rec: tuple) -> int:  # pragma: no cover - compiled
    """Sensors of a cycle (:mod:`._loop`, items 1-2); records the true and sensed state.
    ``kr`` is the cycle's row in the reference arrays, ``k`` in the records (and ``noise``),
    ``j`` the record row the delayed pose sensor reads; ``first``: the run's first cycle (the
    filters start there); with ``exact`` the encoders read ``s_exact`` (the plant's true
    displacement) and the first-order estimate is left out: the caller takes the pose (unless
    from the pose sensor) and the rate from the direct kinematics of the reading, and the
    reference's joint arrays and ``rate_map`` are not read (they may be empty). The arrays
    come in groups: ``ref`` the reference (``q_ref, s_ref_p, Bt_p, s_ref_c, rate_map``: the task
    coordinates, the plant's and the controller's joint references and the rate map), ``filt``
    the encoders (``res, T, a_v, a_a``: resolution, cycle, the two filters' gains), ``mem`` the
    sensors' memory (``s_prev, sd_prev, yq, yqd, ys, ysd, ysdd``), ``rec`` the records
    (``out_q, out_qd, out_att, out_s, out_qs, out_qds, out_se, out_sde, out_sdde``).
    Returns the index of a coordinate beyond its divergence limit (or not finite), else -1."""
    q_ref, s_ref_p, Bt_p, s_ref_c, rate_map = ref
    res, T, a_v, a_a = filt
    s_prev, sd_prev, yq, yqd, ys, ysd, ysdd = mem
    out_q, out_qd, out_att, out_s, out_qs, out_qds, out_se, out_sde, out_sdde = rec
    nq = q.shape[0]
    nu = ys.shape[0]
    for i in range(nq):
        e = q[i] - q_ref[kr, i]
        if not (np.isfinite(e) and np.isfinite(qd[i]) and abs(e) <= div[i]):
            return i
        out_q[k, i] = q[i]
        out_qd[k, i] = qd[i]
    for a in range(nu):
        if exact:
            s = s_exact[a]
        else:
            s = s_ref_p[kr, a]
            for i in range(nq):
                s += Bt_p[kr, a, i] * (q[i] - q_ref[kr, i])
        out_s[k, a] = s
        se = res[a] * np.floor(s / res[a]) if res[a] > 0 else s
        if not first:
            ysd[a] += a_v * ((se - s_prev[a]) / T - ysd[a])
            ysdd[a] += a_a * ((ysd[a] - sd_prev[a]) / T - ysdd[a])
        s_prev[a] = se
        sd_prev[a] = ysd[a]
        ys[a] = se
        out_se[k, a] = se
        out_sde[k, a] = ysd[a]
        out_sdde[k, a] = ysdd[a]
    for i in range(nq):
        out_att[k, i] = out_q[j, i] + noise[k, i]
        if exact:  # the rate (and the pose, unless from the sensor) by the direct kinematics, after
            if pose_from_sensor:
                yq[i] = out_att[k, i]
                out_qs[k, i] = yq[i]
            continue
        r = 0.0
        p = q_ref[kr, i]
        for a in range(nu):
            r += rate_map[kr, i, a] * ysd[a]
            p += rate_map[kr, i, a] * (ys[a] - s_ref_c[kr, a])
        yqd[i] = r
        yq[i] = out_att[k, i] if pose_from_sensor else p
        out_qs[k, i] = yq[i]
        out_qds[k, i] = r
    return -1


@numba.njit(cache=True)
def _actuate(k: int, u_raw: Array, lim: Array, u: Array, out_u: Array, sat: Array) -> None:  # pragma: no cover
    """Clip the efforts to their limits and record them."""
    for a in range(u.shape[0]):
        v = min(max(u_raw[a], -lim[a]), lim[a])
        u[a] = v
        out_u[k, a] = v
        sat[k, a] = abs(u_raw[a]) >= lim[a]
