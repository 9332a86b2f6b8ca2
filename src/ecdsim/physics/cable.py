"""A closed cable loop that synchronises two adjacent hinges of a wing.

Multi-panel arrays open their panels together with closed control (cable) loops, CCLs,
between the yoke-panel and panel-panel hinges, so that the panels open by similar
angles and latch nearly together (e.g. the yoke-and-two-panel arrays tested on ground
in doi:10.1007/978-81-322-2229-3_2, section 1). A cable runs along a panel from a pulley
fixed to the inboard panel at one hinge to a pulley fixed to the outboard panel at the
next, so that the two hinges turn in a fixed ratio (docs/wing.md). Its two strands are
pretensioned; a
rotation of the outboard pulley by ``delta`` against the ratio stretches one strand by
``rho delta`` and relaxes the other by as much (rho the pulley radius), and the loop
returns a torque ``tau = -2 k_s rho^2 delta`` while both strands are taut (k_s the
strand's axial stiffness; Hooke's law on each strand, the torque their tension
difference times rho). A strand goes slack when its tension change reaches the
pretension T0, i.e. at ``|tau| = 2 T0 rho``; beyond, only the other strand carries:

    |delta| <= delta_s:  tau = -K delta,                          K = 2 k_s rho^2
    |delta| >  delta_s:  tau = -sign(delta) (tau_s + K |delta|) / 2,   tau_s = 2 T0 rho

with ``delta_s = tau_s / K``: the loop's stiffness halves where a strand slackens. Here K
is the loop's torsional stiffness with both strands taut and ``tau_s`` the slack torque,
both at the outboard hinge, so the law needs no pulley geometry of its own. The angles
are deployed angles (0 at release, growing towards the latch), and the ratio r couples
them: ``delta = phi_outboard - r phi_inboard``; the loop's torque acts on the outboard
hinge as ``tau`` and on the inboard hinge as ``-r tau`` (virtual work). The strands
themselves are Hooke's law; the halving of the stiffness when one strand slackens is
that of any pretensioned pair (a preloaded bolt joint is the textbook case).
"""

import math


def cable_torque(deflection: float, stiffness: float, slack_torque: float) -> float:
    """Torque of the loop on the outboard hinge, ``tau(delta)`` [N*m].

    Hooke's law on two pretensioned strands, one of which slackens beyond
    ``|tau| = slack_torque`` (the closed loops of doi:10.1007/978-81-322-2229-3_2,
    section 1; module docstring).

    Parameters
    ----------
    deflection : delta = phi_outboard - r phi_inboard [rad]
    stiffness : K, the loop's stiffness with both strands taut, outboard [N*m/rad], > 0
    slack_torque : tau_s = 2 T0 rho, the torque at which a strand slackens [N*m], >= 0

    >>> cable_torque(0.01, 100.0, 2.0), cable_torque(0.03, 100.0, 2.0)
    (-1.0, -2.5)
    """
    limit = slack_torque / stiffness
    if abs(deflection) <= limit:
        return -stiffness * deflection
    return -math.copysign(0.5 * (slack_torque + stiffness * abs(deflection)), deflection)


def cable_energy(deflection: float, stiffness: float, slack_torque: float) -> float:
    """Elastic energy of the loop, ``-int_0^delta tau(u) du`` [J].

    The integral of :func:`cable_torque` (Hooke's law per strand of the closed loops of
    doi:10.1007/978-81-322-2229-3_2, section 1; module docstring):
    ``K delta^2 / 2`` while both strands are taut, then
    ``K delta_s^2 / 2 + tau_s (|delta| - delta_s) / 2 + K (delta^2 - delta_s^2) / 4``.

    Parameters
    ----------
    deflection : delta [rad]
    stiffness : K [N*m/rad], > 0
    slack_torque : tau_s [N*m], >= 0

    >>> round(cable_energy(0.01, 100.0, 2.0), 12), round(cable_energy(0.03, 100.0, 2.0), 12)
    (0.005, 0.0425)
    """
    limit = slack_torque / stiffness
    magnitude = abs(deflection)
    if magnitude <= limit:
        return 0.5 * stiffness * deflection * deflection
    return (
        0.5 * stiffness * limit * limit
        + 0.5 * slack_torque * (magnitude - limit)
        + 0.25 * stiffness * (magnitude * magnitude - limit * limit)
    )
