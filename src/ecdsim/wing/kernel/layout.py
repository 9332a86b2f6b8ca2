"""The wing's words: one float array holding a wing case's constants and modes.

A wing (:mod:`ecdsim.wing`) runs on the kernel's stepper and locator with the same
calling convention as the hinge (``derivatives(cw, y, dy, dm, da, dq)``), so everything a
wing's equations read is one float array ``cw``: a header, then per-hinge, per-group and
per-cable fields stored field by field (``cw[base + field * NMAX + j]``), then each
hinge's drive table. Groups are the hinges joined by rigid cables (one coordinate psi
each; ``phi_j = factor_j psi_group``); a wing without rigid cables has one group per
hinge. The state is ``y = [psi (m), psi' (m), z (a), quadratures (4 n)]``: ``z`` the
heated dampers' log temperature states (:mod:`ecdsim.physics.thermal`), each followed by
its housing's temperature rise where the damper has two nodes, the quadratures
each hinge's damper, friction, latch-damper and gear-mesh dissipation.
"""

from __future__ import annotations

NMAX = 8  # the most hinges (and groups, and cables) a wing case holds

# --- header -------------------------------------------------------------------------------
(
    W_N,  # hinges
    W_M,  # groups (coordinates)
    W_C,  # elastic cables
    W_K,  # table points per hinge (the longest table; shorter ones repeat their end)
    W_GX,  # gravity's in-plane components [m/s^2] (0 in flight)
    W_GY,
    W_MAX_EVENTS,
    W_STOP,  # stop time [s] (inf: none)
    W_RTOL,
    W_STATUS,  # the run's status code (0 running)
    W_STEPS,  # accepted steps
    W_LATCHES,  # latch rows written
    W_EVENTS,  # event rows written
    W_POINTS,  # points written
    W_OVERFLOW,  # 1 when a buffer was full
    W_SETTLE,  # the settle fraction of a rebound's energy
    W_AUX,  # auxiliary states: each heated damper's log state, each housing's rise
    HEADER,
) = range(18)

# --- per hinge (field * NMAX + j) ----------------------------------------------------------
(
    H_MASS,  # its panel (the panel outboard of the hinge): mass [kg]
    H_CGA,  # centre of gravity along [m]
    H_CGB,  # across [m]
    H_INERTIA,  # about the centre of gravity [kg*m^2]
    H_LENGTH,  # hinge to hinge [m]
    H_OFFLOAD,  # offloaded fraction of its weight [-]
    H_STOWED,  # relative angle at release [rad]
    H_SIGN,  # s: +1 where q grows as the hinge deploys
    H_TRAVEL,  # [rad]
    H_JD,  # the ECD's rotor and gear train reflected to the hinge [kg*m^2]
    H_DAMPING,  # BECD_T at the hinge [N*m*s/rad]
    H_FRICTION,  # kinetic FECD_T + FS_T [N*m]
    H_BREAKAWAY,  # f_D FECD_T + f_S FS_T [N*m]
    H_LATCH_K,  # a compliant latch's stiffness [N*m/rad]; 0: rigid
    H_LATCH_C,  # its damping [N*m*s/rad]
    H_RESTITUTION,  # a rigid latch's e
    H_GROUP,  # its group
    H_FACTOR,  # phi = factor psi_group
    H_ENGAGED,  # 1 once its compliant latch engaged
    H_POINTS,  # its table's points
    H_PEAK,  # its compliant latch's peak |torque| so far [N*m]
    H_LAW,  # its ECD's eddy law code (ecdsim.physics.eddy; linear with BD = 0: none)
    H_LA,  # the law's first parameter (BD or T_peak)
    H_LB,  # its second (unused or omega_peak_ref)
    H_RATIO,  # N
    H_BG,  # BG at the high-speed shaft [N*m*s/rad]
    H_FA,  # the law's temperature factor at the ambient temperature [-]
    H_COEF,  # c, the factor's fractional change per kelvin [1/K]
    H_AUX,  # the state index of its damper's log temperature state; -1: not heated
    H_HC,  # the damper's heat capacity [J/K]
    H_HR,  # its thermal resistance to ambient [K/W] (inf: adiabatic)
    H_PEAK_LOG,  # the largest log temperature state of its damper so far [K] (0: ambient)
    H_HOUSING,  # the state index of its housing's rise (two nodes); -1: one node or none
    H_HCH,  # the housing's heat capacity [J/K]
    H_HRHE,  # the housing's resistance to the environment [K/W] (inf: adiabatic)
    H_S0,  # its damper's log temperature state at release [K] (a warm start; 0: ambient)
    H_H0,  # its housing's rise at release [K]
    H_WST,  # its ECD's Stribeck speed at the hinge [rad/s] (inf: none)
    H_EXCESS,  # its Stribeck excess, breakaway less kinetic friction [N*m] (0: none)
    H_ETAF,  # its lossy gear's forward mesh efficiency [-] (1: ideal)
    H_ETAB,  # its back-driven mesh efficiency [-] (1: ideal)
    H_FQ,  # FECD_T through an ideal gear, FT N [N*m] (FECD_T without a lossy gear)
    H_FLOW,  # its lossy gear's power flow: +1 forward, -1 back-driven, 0 ideal or at rest
    H_HINT,  # the flow a power_flow event switched it to (0: decide from the state)
    H_GAP,  # its gear's lost motion at the hinge [rad] (0: none)
    H_MESHED,  # 1 once its lost motion closed (the damper side engaged); 1 without one
    H_FE,  # its ECD's kinetic friction FECD_T [N*m] (part of H_FRICTION once meshed)
    H_FEB,  # its ECD's breakaway f_D FECD_T [N*m] (part of H_BREAKAWAY once meshed)
    HFIELDS,
) = range(49)
HINGES = HEADER

# --- per group ------------------------------------------------------------------------------
(
    G_DIR,  # +1 / -1 sliding, 0 at rest (stuck or locked)
    G_LOCKED,  # 1 latched (rigid latch)
    G_FRICTION,  # P^T friction [N*m]
    G_BREAKAWAY,  # P^T breakaway [N*m]
    G_TRAVEL,  # [rad] in psi
    G_RIGID,  # 1: a rigid latch
    G_FIRST,  # its first (innermost) hinge
    G_ARRIVED,  # 1 after its first arrival
    G_ARRIVAL_KE,  # the wing's kinetic energy then [J]
    G_LATCH_ROW,  # its latch row in the latch buffer
    GFIELDS,
) = range(11)
GROUPS = HINGES + HFIELDS * NMAX

# --- per elastic cable ------------------------------------------------------------------------
(
    C_IN,  # inboard hinge
    C_RATIO,
    C_K,  # stiffness with both strands taut [N*m/rad]
    C_SLACK,  # slack torque 2 T0 rho [N*m]
    C_SIDE_A,  # the orientation of its two slack events in the current segment
    C_SIDE_B,
    CFIELDS,
) = range(7)
CABLES = GROUPS + GFIELDS * NMAX
TABLES = CABLES + CFIELDS * NMAX


def hinge(field: int, j: int) -> int:
    """The word of hinge j's field."""
    return HINGES + field * NMAX + j


def group(field: int, g: int) -> int:
    """The word of group g's field."""
    return GROUPS + field * NMAX + g


def cable(field: int, c: int) -> int:
    """The word of elastic cable c's field."""
    return CABLES + field * NMAX + c


def words(points: int) -> int:
    """The length of a wing case's words with tables of ``points`` points."""
    return TABLES + 2 * NMAX * points


def table_angle(cw_points: int, j: int, p: int) -> int:
    """The word of hinge j's table angle p (tables of ``cw_points`` points)."""
    return TABLES + j * cw_points + p


def table_torque(cw_points: int, j: int, p: int) -> int:
    """The word of hinge j's table torque p."""
    return TABLES + NMAX * cw_points + j * cw_points + p


# --- events -------------------------------------------------------------------------------------
# Slots of a segment: per group its motion (a sliding one's speed reaching zero, a stuck
# one's holding torque reaching its breakaway), per group its geometric event (its latch
# ahead, or the stowed stop behind), per elastic cable its two slack points, per hinge
# its lossy gear's power flow switching, per hinge its lost motion closing.
FLOW_SLOTS = 4 * NMAX
GAP_SLOTS = 5 * NMAX
SLOTS = 6 * NMAX
(
    EV_RELEASE,
    EV_BREAKAWAY,
    EV_STICK,
    EV_ZERO,
    EV_LATCH,
    EV_REBOUND,
    EV_SETTLE,
    EV_ENGAGE,
    EV_START_STOP,
    EV_SLACK,
    EV_TAUT,
    EV_CREEP,
    EV_STOP_TIME,
    EV_EVENT_LIMIT,
    EV_POWER_FLOW,
    EV_GEAR_ENGAGE,
) = range(16)
# The names of :data:`ecdsim.wing.result.EVENT_KINDS`, in code order.
EVENT_NAMES = (
    "release",
    "breakaway",
    "stick",
    "zero_speed",
    "latch",
    "rebound",
    "settle",
    "latch_engage",
    "start_stop",
    "slack",
    "taut",
    "creep",
    "stop_time",
    "event_limit",
    "power_flow",
    "gear_engage",
)
(ST_RUNNING, ST_LATCHED, ST_STUCK, ST_CREEP, ST_STOP_TIME, ST_EVENT_LIMIT) = range(6)
STATUS_NAMES = ("running", "latched", "stuck", "creep", "stop_time", "event_limit")

# --- buffers ------------------------------------------------------------------------------------
# A latch row: hinge (its group's first), time, speed, kinetic energy, impact loss,
# impulse.
LATCH_HINGE, LATCH_TIME, LATCH_SPEED, LATCH_KE, LATCH_LOSS, LATCH_IMPULSE, LATCH_FIELDS = range(7)
# An event row: time, kind, hinge (-1: none).
EVENT_FIELDS = 3
