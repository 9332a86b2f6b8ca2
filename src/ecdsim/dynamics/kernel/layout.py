"""The kernel's data layout: the case's words, modes, events, outputs.

A running case is one float array, its *words* ``cw``: its constants (a row of the case
table, the columns below), then its discrete state (``MD_*``: friction modes, the
spring piece, the mesh's mode ...), then the current segment's constants (``SG_*``),
then the segment's projected inverse mass matrix (``PINV``, m x m). One array, so that
the kernel's functions take one argument for all of it (numba passes every array as a
structure of several words), plus its spring tables. Event codes are the indices of
:data:`ecdsim.dynamics.result.EVENT_KINDS` and statuses those of
:data:`~ecdsim.dynamics.result.STATUSES` (checked by tests/test_dynamics_kernel.py).
"""

from __future__ import annotations

from ecdsim.dynamics.kernel import effects as _registry

# --- the case table: one row per case ---------------------------------------------------
(
    JL,  # load inertia at the input shaft [kg*m^2]
    JD,  # damper side (rotor and gear train) reflected to the input [kg*m^2]
    FS,  # system friction FS_T, kinetic [N*m]
    FSB,  # its breakaway f_S FS_T [N*m]
    FE,  # ECD friction FECD_T, kinetic [N*m] (a lossy gear's 1/eta_f included)
    FEB,  # its breakaway f_D FECD_T [N*m]
    WST,  # Stribeck speed at the input [rad/s]; inf: none
    TRAVEL,  # end of travel [rad]
    REST,  # restitution at the stops [-]
    GAP,  # lost motion b [rad]
    PHI0,  # angle at release [rad]
    W0,  # load speed at release [rad/s]
    LAW,  # eddy law code (ecdsim.physics.eddy)
    LA,  # its first parameter (BD or T_peak)
    LB,  # its second (unused, omega_peak_ref, or the power law's n)
    LC,  # its third (the power law's linear-core speed omega_l [rad/s]; else unused)
    COEF,  # c, the law's temperature factor per kelvin [1/K]
    FA,  # f_a, the factor at the ambient temperature [-]
    RATIO,  # N [-]
    BG,  # BG at the high-speed shaft [N*m*s/rad]
    BLIN,  # BECD_T at ambient (a lossy gear's 1/eta_f included) [N*m*s/rad]
    NODES,  # heating: 0 none, 1 the damper, 2 rotor and housing
    HC,  # heat capacity (rotor's with two nodes) [J/K]
    HR,  # thermal resistance to ambient (rotor to housing with two nodes) [K/W]
    HCH,  # housing heat capacity [J/K]
    HRHE,  # housing to ambient [K/W]
    S0,  # the damper's log state at release [K]
    H0,  # the housing's rise at release [K]
    AMB,  # ambient (deployment) temperature [degC]
    TZERO,  # the law's zero temperature T_ref - 1/c where c < 0, else inf [degC]
    ETAF,  # forward mesh efficiency [-]
    ETAB,  # back-driven mesh efficiency [-]
    MC,  # mesh stiffness c [N*m/rad]; inf: rigid
    MD,  # mesh damping d [N*m*s/rad]
    TREF,  # the damping law's reference temperature, where its factor is 1 [degC]
    EFFECTS,  # the effects the case has (EFFECT_* bits)
    BUILT_IN_COLUMNS,
) = range(37)
# Then one column per parameter of the registered effects (ecdsim.dynamics.kernel.effects).
COLUMNS = _registry.END_COLUMN
if BUILT_IN_COLUMNS != _registry.FIRST_COLUMN:  # the registry's columns follow EFFECTS
    raise ImportError("effects.FIRST_COLUMN must be layout.BUILT_IN_COLUMNS")

# --- effects: what a case has beyond the paper's rigid linear hinge ---------------------
# Each path of the kernel lists the effects it models; a case with any other is refused
# (gates closed by default: a new effect is unknown to every path until it is added).
EFFECT_ROLLOFF = 1  # the Kloss law (roll-off) instead of Eq. 1's linear one
EFFECT_HEATING = 2  # self-heating (one node)
EFFECT_TWO_NODE = 4  # the housing as a second node
EFFECT_STRIBECK = 8  # a Stribeck speed
EFFECT_LOSSY = 16  # a lossy gear
EFFECT_LOST_MOTION = 32  # a rigid mesh's lost motion
EFFECT_COMPLIANT = 64  # a compliant mesh (two coordinates)
EFFECT_RESISTANCE = 128  # a resistive table
EFFECT_REBOUND = 256  # a rebounding end stop
EFFECT_WARM_START = 512  # heat carried over from a previous deployment
EFFECT_STOP_TIME = 1024  # a stop time
EFFECT_POWER_LAW = 2048  # a shear-thinning fluid damper's power law (physics.fluid)
# (gravity is a registered effect: kernel/effects.py)
# The effects the kernel models (every path together: the built-in ones and the
# registered ones, whose bits follow), and those a closed-form segment takes: linear
# damping at a constant temperature, Coulomb friction, and the registered
# effects that declare it.
BUILT_IN_EFFECTS = 4095
if BUILT_IN_EFFECTS + 1 != _registry.FIRST_BIT:
    raise ImportError("effects.FIRST_BIT must follow layout.BUILT_IN_EFFECTS")
KERNEL_EFFECTS = BUILT_IN_EFFECTS | _registry.REGISTERED_BITS
CLOSED_FORM_EFFECTS = (
    EFFECT_LOSSY | EFFECT_LOST_MOTION | EFFECT_RESISTANCE | EFFECT_REBOUND | EFFECT_STOP_TIME
) | _registry.CLOSED_FORM_BITS
# Effects that act on a segment only while the damper side is engaged.
ENGAGED_EFFECTS = (
    EFFECT_ROLLOFF | EFFECT_HEATING | EFFECT_TWO_NODE | EFFECT_WARM_START | EFFECT_POWER_LAW
)

# --- run settings (a float array shared by the cases) -----------------------------------
STOP, RTOL, MAX_EVENTS, RECORD, METHOD, SETTINGS = range(6)
# settings[METHOD]: the integrator of nonlinear segments (RODAS4, or scipy's by name).
INTEGRATOR_CODES = {"RODAS4": 0, "Radau": 1, "BDF": 2, "LSODA": 3}

# --- the case's discrete state (words after the columns) --------------------------------
(
    MD_SLIDE0,  # friction element 0 (the load, or the rigid hinge): +1, -1, 0 at rest
    MD_SLIDE1,  # element 1 (the damper side of a compliant mesh)
    MD_ENGAGED,  # rigid mesh: 1 once the lost motion has closed
    MD_PIECE,  # the load's spring piece
    MD_FLOW,  # lossy gear: +1 forward, -1 back-driven, 0 ideal or free
    MD_HINT,  # the flow a power_flow event switched to (0: decide from the state)
    MD_MESH,  # compliant mesh: MESH_GAP, PRESS or RELEASED
    MD_SIDE,  # its flank: +1 the load drives, -1 backward
    MD_HELD,  # the load held at the end of travel: 0, or its status code
    MD_START,  # the load at rest against the start stop
    MD_DONE,  # the run's status once finished (0 running)
    MD_PASSES,  # passes that ended in an event other than a breakpoint
    MD_IMPACTS,  # rebounding impacts
    MD_STEPS,  # integrator steps taken so far
    MD_END,
) = range(COLUMNS, COLUMNS + 15)
MD_FIELDS = MD_END - COLUMNS
MESH_GAP, PRESS, RELEASED = 0, 1, 2

# --- a segment's constants (words after the state) --------------------------------------
(
    SG_PHI,  # the load's angle at the segment's start [rad] (the state's q0 is from here)
    SG_T0,  # the net spring torque there (the spring less the resistive table) [N*m]
    SG_SLOPE,  # its dT/dphi on the piece [N*m/rad]
    SG_R0,  # the resistive table's torque at the start [N*m]
    SG_RSLOPE,  # its slope [N*m/rad]
    SG_FC0,  # element 0's kinetic friction in the segment [N*m]
    SG_EX0,  # its Stribeck excess at rest [N*m]
    SG_FC1,  # element 1's
    SG_EX1,
    SG_MESH,  # a lossy gear's factor m on the damper side (1 ideal)
    SG_ENG,  # 1 engaged, 0 free (the rigid mesh's lost motion)
    SG_TARGET,  # the load's geometric event ahead, from the segment's start [rad]
    SG_REACH,  # its event code
    SG_CREEP,  # the speed below which an approach to rest is creep [rad/s]
    SG_FQ,  # a lossy gear's ideal ECD friction F_q [N*m]
    SG_DRIVE,  # the forward-frame drive at the start: sigma T_s - kinetic friction [N*m]
    SG_LOAD,  # a lossy gear's load drive A_0: sigma T_s - FS_T [N*m]
    SG_END,
) = range(MD_END, MD_END + 18)
SG_FIELDS = SG_END - MD_END
PINV = SG_END  # the projected inverse mass, row-major (m x m)


def case_words(m: int) -> int:
    """The length of a case's words with m coordinates."""
    return PINV + m * m


# --- event slots of a segment (the locator's functions) ---------------------------------
(
    SLOT_REACH,  # the load's geometric event
    SLOT_ZERO0,  # element 0 sliding: its speed falls to 0
    SLOT_ZERO1,
    SLOT_BREAK0,  # element 0 stuck: its holding torque reaches its breakaway
    SLOT_BREAK1,
    SLOT_MESH_A,  # compliant mesh events (see hinge.mesh_events)
    SLOT_MESH_B,
    SLOT_SWITCH,  # a lossy gear's power flow reverses
    SLOT_CREEP,  # asymptotic approach to rest (accepted with an equilibrium ahead)
    SLOTS,
) = range(10)
CAP_SLOT, HORIZON_SLOT = 100, 101  # a segment that ended at its time cap or horizon

# --- event kinds and statuses (indices into result.EVENT_KINDS / STATUSES) ---------------
(
    EV_RELEASE,
    EV_BREAKAWAY,
    EV_STICK,
    EV_ZERO,
    EV_ENGAGE,
    EV_BREAKPOINT,
    EV_ARRIVE,
    EV_LATCH,
    EV_SETTLE,
    EV_START_STOP,
    EV_STOP_TIME,
    EV_CREEP,
    EV_EVENT_LIMIT,
    EV_HORIZON,
    EV_SEPARATE,
    EV_CONTACT,
    EV_POWER_FLOW,
) = range(17)
(
    ST_RUNNING,
    ST_LATCHED,
    ST_SETTLED,
    ST_STUCK,
    ST_CREEP,
    ST_STOP_TIME,
    ST_EVENT_LIMIT,
    ST_HORIZON,
) = range(8)

# --- a case's summary (one row per case) ------------------------------------------------
(
    OUT_ARRIVAL_TIME,
    OUT_ARRIVAL_SPEED,
    OUT_ARRIVAL_KE,
    OUT_TIME,
    OUT_ANGLE,
    OUT_SPEED,
    OUT_TEMPERATURE,
    OUT_STUCK_ANGLE,
    OUT_STUCK_TIME,
    OUT_MAX_SPEED,
    OUT_MAX_TEMPERATURE,
    OUT_ENGAGEMENT_TIME,
    OUT_REBOUND_SPEED,
    OUT_SPRING_WORK,
    OUT_RESISTIVE_WORK,
    OUT_INITIAL_KE,
    OUT_DAMPER_WORK,
    OUT_FRICTION_WORK,
    OUT_ENGAGEMENT_LOSS,
    OUT_IMPACT_LOSS,
    OUT_FINAL_KE,
    OUT_GEAR_LOSS,
    OUT_MESH_WORK,
    OUT_ELASTIC,
    OUT_MAX_MESH_TORQUE,
    OUT_LATCH_MESH_TORQUE,
    OUT_HOUSING,
    OUT_STATUS,
    OUT_IMPACTS,
    OUT_STUCK,
    OUT_HOLD_FROM,
    OUT_DISPLAY_END,
    OUT_ENGAGED,
    OUT_START_KE,
    OUT_FIELDS,
) = range(35)

# --- recorded spans (time series): one row per segment ----------------------------------
(
    SPAN_CASE,
    SPAN_KIND,  # SPAN_CLOSED or SPAN_STEPS
    SPAN_T0,
    SPAN_T1,
    SPAN_PHI0,  # the load's angle at the start [rad]
    SPAN_DIR,  # direction of the closed form's frame
    SPAN_J,  # closed form: J, B, k, a, w0 of J x'' + B x' + k x = a
    SPAN_B,
    SPAN_K,
    SPAN_A,
    SPAN_W0,
    SPAN_TEMP,  # the damper's temperature in a closed-form span [degC]
    SPAN_ENGAGED,
    SPAN_FIRST,  # integrated: the first row of its points
    SPAN_COUNT,  # and their number
    SPAN_FIELDS,
) = range(16)
SPAN_CLOSED, SPAN_STEPS = 0, 1
# A recorded point of an integrated span: time, load angle, load speed, damper log state
# and their rates (cubic Hermite between points).
POINT_T, POINT_PHI, POINT_W, POINT_S, POINT_DPHI, POINT_DW, POINT_DS, POINT_FIELDS = range(8)
# An event row: case, time, kind, angle, speed.
EVENT_FIELDS = 5
