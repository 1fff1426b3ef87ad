"""Grubler-Kutzbach mobility counts and reference data for classic mechanisms.

Kutzbach (spatial):  M = 6 (N - 1 - j) + sum f_k
Grubler  (planar):   M = 3 (N - 1 - j) + sum f_k
N = number of rigid bodies INCLUDING the fixed base, j = number of joints,
f_k = freedoms of joint k.  References: K. Kutzbach, "Mechanische
Leitungsverzweigung", Maschinenbau 8 (1929); Hunt, *Kinematic Geometry of
Mechanisms*, OUP 1978; Tsai, *Robot Analysis*, Wiley 1999, sec. 1.4;
Merlet, *Parallel Robots*, 2nd ed., Springer 2006, sec. 4.x; G. Gogu,
"Chebychev-Grubler-Kutzbach's criterion for mobility calculation of
multi-loop mechanisms revisited via theory of linear transformations",
Eur. J. Mech. A/Solids 24 (2005) 427-441.

Bookkeeping used in ``CLASSIC``:
  true mobility M = kutzbach - idle + overconstraints
  idle            = passive freedoms that move no other body (spins of a
                    bar about the line of its two spherical joints)
  overconstraints = redundant (dependent) closure constraints.
"""

from __future__ import annotations

JOINT_FREEDOMS = {
    "R": 1,  # revolute
    "P": 1,  # prismatic
    "H": 1,  # helical
    "C": 2,  # cylindrical
    "U": 2,  # universal (Hooke)
    "S": 3,  # spherical
    "E": 3,  # planar pair (plane contact)
}


def joint_freedom(j):
    """Freedoms of one joint: an int, or a type letter from JOINT_FREEDOMS."""
    if isinstance(j, str):
        return JOINT_FREEDOMS[j.upper()]
    return int(j)


def kutzbach(n_bodies, joints, space="spatial"):
    """Grubler-Kutzbach count.

    n_bodies: number of bodies including the base; joints: iterable of joint
    types ("R", "P", "H", "C", "U", "S", "E") or integer freedoms;
    space: "spatial" (lambda = 6) or "planar" (lambda = 3).
    Returns int M = lambda (n_bodies - 1 - j) + sum f.
    """
    lam = {"spatial": 6, "planar": 3}[space]
    js = list(joints)
    return lam * (n_bodies - 1 - len(js)) + sum(joint_freedom(j) for j in js)


def loops(n_bodies, n_joints):
    """Number of independent loops (Euler): j - N + 1."""
    return n_joints - n_bodies + 1


# name -> dict(n_bodies, joints, mobility, kutzbach spatial / planar, idle,
# overconstraints (spatial count), source)
CLASSIC = {
    "planar_four_bar": {
        "n_bodies": 4, "joints": ["R"] * 4, "mobility": 1,
        "kutzbach_spatial": -2, "grubler_planar": 1, "idle": 0, "overconstraints": 3,
        "source": "Hunt 1978; Tsai 1999 sec. 1.4; Gogu 2005",
    },
    "bennett": {
        "n_bodies": 4, "joints": ["R"] * 4, "mobility": 1,
        "kutzbach_spatial": -2, "grubler_planar": None, "idle": 0, "overconstraints": 3,
        "source": "Bennett 1903/1914; Hunt 1978; McCarthy 2000; Gogu 2005",
    },
    "stewart_6UPS": {
        # base + platform + 6 x (cylinder, piston)
        "n_bodies": 14, "joints": ["U"] * 6 + ["P"] * 6 + ["S"] * 6, "mobility": 6,
        "kutzbach_spatial": 6, "grubler_planar": None, "idle": 0, "overconstraints": 0,
        "source": "Merlet 2006; Tsai 1999",
    },
    "stewart_6SPS": {
        "n_bodies": 14, "joints": ["S"] * 6 + ["P"] * 6 + ["S"] * 6, "mobility": 6,
        "kutzbach_spatial": 12, "grubler_planar": None, "idle": 6, "overconstraints": 0,
        "source": "Merlet 2006; Tsai 1999 (6 idle leg spins about the leg axes)",
    },
    "delta_3R_SS_parallelogram": {
        # base + platform + 3 upper arms + 6 forearm bars; each parallelogram
        # modelled as two S-S bars (Clavel's ball-jointed forearms)
        "n_bodies": 11, "joints": ["R"] * 3 + ["S"] * 12, "mobility": 3,
        "kutzbach_spatial": 9, "grubler_planar": None, "idle": 6, "overconstraints": 0,
        "source": "Clavel 1988; Tsai 1999; Williams 2016 (6 idle bar spins)",
    },
    "planar_3RRR": {
        # base + 3 x (proximal, distal) + platform
        "n_bodies": 8, "joints": ["R"] * 9, "mobility": 3,
        "kutzbach_spatial": -3, "grubler_planar": 3, "idle": 0, "overconstraints": 6,
        "source": "Gosselin & Angeles 1990; Merlet 2006",
    },
}
