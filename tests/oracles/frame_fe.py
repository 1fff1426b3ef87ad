"""Linear static finite elements for 3-D frames of Euler-Bernoulli beams (direct stiffness method).

A small reference solver for the static compliance of frames, rigid links, joints and
actuator springs. Sources: J. S. Przemieniecki, *Theory of Matrix Structural Analysis*,
McGraw-Hill 1968, ch. 5 (beam element, transformation) and ch. 9 (constraints);
W. McGuire, R. H. Gallagher & R. D. Ziemian, *Matrix Structural Analysis*, 2nd ed., Wiley
2000, ch. 4-5 (space frame element, direct stiffness assembly, rigid offsets and releases).
Linear elastic, small displacements, shear deformation neglected (Euler-Bernoulli), uniform
St-Venant torsion ``G J`` (no warping), no geometric stiffness.

Degrees of freedom (all global): node ``i`` owns ``(u_x, u_y, u_z, th_x, th_y, th_z)`` [m, rad];
a load is ``(F_x, F_y, F_z, M_x, M_y, M_z)`` [N, N m]. ``dofs`` arguments use 0-2 for the
translations and 3-5 for the rotations about the global axes.

Element (nodes 1 -> 2, length ``L``): local axes ``e_x = (x2 - x1)/L``; ``e_z`` = the part of the
reference vector ``up`` normal to ``e_x`` (normalised); ``e_y = e_z x e_x``. So ``up`` lies in
the local x-z plane; ``I_z`` resists deflection along local y, ``I_y`` along local z. Default
``up``: global z, or global y when ``|e_x . z| > 0.9`` (then e_z = y, e_y = x for a beam along +z).
Local stiffness on ``(u1, th1, u2, th2)`` (12 x 12):

* axial ``EA/L [[1, -1], [-1, 1]]`` on ``(u_x1, u_x2)``; torsion ``GJ/L [[1, -1], [-1, 1]]``
  on ``(th_x1, th_x2)``;
* bending in x-y (``th_z = dv/dx``), on ``(u_y1, th_z1, u_y2, th_z2)``:
  ``EI_z/L^3 [[12, 6L, -12, 6L], [6L, 4L^2, -6L, 2L^2], [-12, -6L, 12, -6L], [6L, 2L^2, -6L, 4L^2]]``;
* bending in x-z (``th_y = -dw/dx``), on ``(u_z1, th_y1, u_z2, th_y2)``: the same with every
  ``6L`` term negated.

Global element matrix ``K_e = Lam^T k Lam``, ``Lam = diag(R, R, R, R)``, rows of ``R`` =
``e_x, e_y, e_z`` (``u_local = R u_global``). The cubic Hermite element is nodally exact for end
loads, so ``segments > 1`` gives the same answer at the end nodes (and the exact elastic line
at the intermediate nodes).

Springs: ``spring(node, dof, k)`` adds ``k`` to one diagonal entry (grounded);
``spring_between(a, b, n, k)`` adds ``k [[n n^T, -n n^T], [-n n^T, n n^T]]`` on the two nodes'
translations (a linearised axial spring along the unit vector ``n``).

Constraints, all homogeneous linear rows ``C u = 0``:

* ``support(node, dofs)``: ``u_d = 0``;
* ``couple(a, b, dofs)``: ``u_{b,d} - u_{a,d} = 0`` (nodes at the same place; translations
  only = spherical joint, translations + two rotations = revolute about the third axis);
* ``add_rigid(m, s)``: ``u_s = u_m + th_m x r`` (``r = x_s - x_m``), ``th_s = th_m``.

Elimination (master-slave transformation in its general form): ``u = T q`` with ``T`` an
orthonormal basis of the null space of ``C`` (SVD of the rows, each normalised; dofs that
appear in no row keep identity columns); then ``K_r = T^T K T``, ``f_r = T^T f`` (virtual
work) and ``K_r q = f_r``. Chains and redundant constraints need no special order.
Mechanism test: with ``D = diag(K_r)``, ``S = D^-1/2 K_r D^-1/2``; the structure is a mechanism
(``MechanismError``) if some ``D_ii <= 0`` or ``lambda_min(S) < tol * lambda_max(S)``
(``tol = 1e-12`` by default). Compliance of a node: ``T_n K_r^-1 T_n^T``, ``T_n`` its 6 rows of T.
"""

from __future__ import annotations

import numpy as np

TRANSLATIONS = (0, 1, 2)
ROTATIONS = (3, 4, 5)
ALL_DOFS = (0, 1, 2, 3, 4, 5)
_DOF_NAMES = ("ux", "uy", "uz", "rx", "ry", "rz")


class MechanismError(np.linalg.LinAlgError):
    """The reduced stiffness matrix is singular: the structure (or part of it) can move freely."""


def _skew(r):
    return np.array([[0.0, -r[2], r[1]], [r[2], 0.0, -r[0]], [-r[1], r[0], 0.0]])


def local_stiffness(L, E, G, A, Iy, Iz, J):
    """12 x 12 local stiffness of a 3-D Euler-Bernoulli beam (dof order see module docstring)."""
    k = np.zeros((12, 12))
    ax = np.array([[1.0, -1.0], [-1.0, 1.0]])
    k[np.ix_([0, 6], [0, 6])] = E * A / L * ax
    k[np.ix_([3, 9], [3, 9])] = G * J / L * ax
    b = np.array(
        [
            [12.0, 6 * L, -12.0, 6 * L],
            [6 * L, 4 * L * L, -6 * L, 2 * L * L],
            [-12.0, -6 * L, 12.0, -6 * L],
            [6 * L, 2 * L * L, -6 * L, 4 * L * L],
        ]
    )
    k[np.ix_([1, 5, 7, 11], [1, 5, 7, 11])] = E * Iz / L**3 * b
    flip = np.array([1.0, -1.0, 1.0, -1.0])  # th_y = -dw/dx: negate the 6L (mixed) terms
    k[np.ix_([2, 4, 8, 10], [2, 4, 8, 10])] = E * Iy / L**3 * b * np.outer(flip, flip)
    return k


def beam_axes(x1, x2, up=None):
    """Rotation R (rows e_x, e_y, e_z) of a beam from x1 to x2 with reference vector ``up``."""
    d = np.asarray(x2, float) - np.asarray(x1, float)
    L = np.linalg.norm(d)
    if L == 0.0:
        raise ValueError("beam of zero length")
    ex = d / L
    if up is None:
        up = (0.0, 1.0, 0.0) if abs(ex[2]) > 0.9 else (0.0, 0.0, 1.0)
    up = np.asarray(up, float)
    ez = up - (up @ ex) * ex
    nz = np.linalg.norm(ez)
    if nz <= 1e-8 * np.linalg.norm(up):
        raise ValueError(f"reference vector up={up} is parallel to the beam axis {ex}")
    ez = ez / nz
    return np.array([ex, np.cross(ez, ex), ez]), L


class Frame:
    """A linear 3-D frame: nodes, beams, springs, rigid links, joints (couplings) and supports."""

    def __init__(self, mechanism_tol=1e-12):
        self.mechanism_tol = mechanism_tol
        self.nodes: list[np.ndarray] = []
        self.elements: list[tuple[int, int, np.ndarray]] = []  # (n1, n2, 12x12 global)
        self._springs: list[tuple[list[int], np.ndarray]] = []  # (global dofs, matrix)
        self._rows: list[dict[int, float]] = []  # constraint rows {global dof: coefficient}

    # -- model -------------------------------------------------------------------------
    def add_node(self, xyz) -> int:
        x = np.asarray(xyz, float).reshape(3)
        self.nodes.append(x)
        return len(self.nodes) - 1

    def _check(self, n):
        if not 0 <= n < len(self.nodes):
            raise IndexError(f"no node {n}")

    def add_beam(self, n1, n2, E, G, A, Iy, Iz, J, up=None, segments=1) -> list[int]:
        """Beam n1 -> n2 in ``segments`` equal elements; returns the node ids along it."""
        self._check(n1)
        self._check(n2)
        if int(segments) < 1:
            raise ValueError("segments must be >= 1")
        x1, x2 = self.nodes[n1], self.nodes[n2]
        R, L = beam_axes(x1, x2, up)
        chain = [n1]
        for i in range(1, int(segments)):
            chain.append(self.add_node(x1 + (x2 - x1) * (i / segments)))
        chain.append(n2)
        lam = np.kron(np.eye(4), R)
        ke = lam.T @ local_stiffness(L / segments, E, G, A, Iy, Iz, J) @ lam
        for a, b in zip(chain[:-1], chain[1:]):
            self.elements.append((a, b, ke))
        return chain

    def add_rigid(self, n_master, n_slave):
        """Rigid link: u_s = u_m + th_m x (x_s - x_m), th_s = th_m."""
        self._check(n_master)
        self._check(n_slave)
        r = self.nodes[n_slave] - self.nodes[n_master]
        S = _skew(r)  # th x r = -S th
        m, s = 6 * n_master, 6 * n_slave
        for i in range(3):
            row = {s + i: 1.0, m + i: -1.0}
            for j in range(3):
                if S[i, j] != 0.0:
                    row[m + 3 + j] = S[i, j]
            self._rows.append(row)
            self._rows.append({s + 3 + i: 1.0, m + 3 + i: -1.0})

    def couple(self, n_a, n_b, dofs):
        """Join the listed global dofs of two coincident nodes (a joint between members)."""
        self._check(n_a)
        self._check(n_b)
        gap = np.linalg.norm(self.nodes[n_a] - self.nodes[n_b])
        scale = max(1.0, max(np.linalg.norm(x) for x in self.nodes))
        if gap > 1e-9 * scale:
            raise ValueError(f"couple: nodes {n_a} and {n_b} are {gap:.3g} m apart (use add_rigid)")
        for d in self._dofs(dofs):
            self._rows.append({6 * n_b + d: 1.0, 6 * n_a + d: -1.0})

    def support(self, node, dofs=ALL_DOFS):
        """Fix the listed global dofs of ``node`` to the ground."""
        self._check(node)
        for d in self._dofs(dofs):
            self._rows.append({6 * node + d: 1.0})

    def spring(self, node, dof, k):
        """Grounded linear spring of stiffness k on one global dof."""
        self._check(node)
        (d,) = self._dofs([dof])
        self._springs.append(([6 * node + d], np.array([[float(k)]])))

    def spring_between(self, n_a, n_b, direction, k):
        """Axial translational spring between two nodes along the unit vector ``direction``."""
        self._check(n_a)
        self._check(n_b)
        n = np.asarray(direction, float).reshape(3)
        n = n / np.linalg.norm(n)
        nn = np.outer(n, n)
        idx = [6 * n_a + i for i in range(3)] + [6 * n_b + i for i in range(3)]
        self._springs.append((idx, float(k) * np.block([[nn, -nn], [-nn, nn]])))

    @staticmethod
    def _dofs(dofs):
        out = [int(d) for d in dofs]
        if any(d < 0 or d > 5 for d in out):
            raise ValueError(f"dofs must lie in 0..5, got {dofs}")
        return out

    # -- assembly and solution ---------------------------------------------------------
    def stiffness(self) -> np.ndarray:
        """Unconstrained global stiffness matrix (6 n_nodes square)."""
        n = 6 * len(self.nodes)
        K = np.zeros((n, n))
        for a, b, ke in self.elements:
            idx = np.r_[6 * a : 6 * a + 6, 6 * b : 6 * b + 6]
            K[np.ix_(idx, idx)] += ke
        for idx, ks in self._springs:
            K[np.ix_(idx, idx)] += ks
        return K

    def transformation(self) -> np.ndarray:
        """T with u = T q: an orthonormal basis of the displacements allowed by the constraints."""
        n = 6 * len(self.nodes)
        if not self._rows:
            return np.eye(n)
        C = np.zeros((len(self._rows), n))
        for i, row in enumerate(self._rows):
            for j, c in row.items():
                C[i, j] += c
        C /= np.linalg.norm(C, axis=1, keepdims=True)
        inv = np.flatnonzero(np.any(C != 0.0, axis=0))  # dofs in some constraint
        free = np.setdiff1d(np.arange(n), inv)
        _, s, vt = np.linalg.svd(C[:, inv])
        rank = int(np.sum(s > 1e-10 * s[0]))
        null = vt[rank:].T
        T = np.zeros((n, len(free) + null.shape[1]))
        T[free, np.arange(len(free))] = 1.0
        T[np.ix_(inv, np.arange(len(free), T.shape[1]))] = null
        return T

    def _reduced(self):
        """(T, D^-1/2, S^-1) with S the Jacobi-scaled reduced stiffness; raises MechanismError."""
        if not self.nodes:
            raise ValueError("empty frame")
        T = self.transformation()
        Kr = T.T @ self.stiffness() @ T
        d = np.diag(Kr).copy()
        dmax = max(np.max(np.abs(d)), 1e-300) if d.size else 1.0
        if np.any(d <= self.mechanism_tol * dmax):
            j = int(np.argmin(d))
            raise MechanismError(f"mechanism: no stiffness on {self._describe(T[:, j])}")
        w = 1.0 / np.sqrt(d)
        S = Kr * np.outer(w, w)
        S = 0.5 * (S + S.T)
        lam, vec = np.linalg.eigh(S)
        if lam[0] < self.mechanism_tol * lam[-1]:
            nz = int(np.sum(lam < self.mechanism_tol * lam[-1]))
            raise MechanismError(
                f"mechanism: singular stiffness (lambda_min/lambda_max = {lam[0] / lam[-1]:.2e} "
                f"after diagonal scaling, {nz} zero mode(s)); first mode moves "
                + self._describe(T @ (w * vec[:, 0]))
            )
        Sinv = (vec / lam) @ vec.T
        return T, w, Sinv

    def _describe(self, u):
        u = np.abs(u)
        top = np.argsort(u)[::-1][:4]
        return ", ".join(f"node {j // 6} {_DOF_NAMES[j % 6]}" for j in top if u[j] > 1e-3 * u[top[0]])

    def solve(self, loads) -> dict[int, np.ndarray]:
        """Displacements (3 translations [m], 3 rotations [rad], global) of every node."""
        f = np.zeros(6 * len(self.nodes))
        for node, load in loads.items():
            self._check(node)
            f[6 * node : 6 * node + 6] += np.asarray(load, float).reshape(6)
        T, w, Sinv = self._reduced()
        u = T @ (w * (Sinv @ (w * (T.T @ f))))
        return {i: u[6 * i : 6 * i + 6].copy() for i in range(len(self.nodes))}

    def compliance(self, node) -> np.ndarray:
        """6 x 6 compliance of ``node``: displacement per unit force / moment applied there."""
        self._check(node)
        T, w, Sinv = self._reduced()
        Tn = T[6 * node : 6 * node + 6] * w
        C = Tn @ Sinv @ Tn.T
        return 0.5 * (C + C.T)
