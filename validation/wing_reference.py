"""An independent reference for a wing's deployment: Lagrange's equations of the panel
chain, derived with sympy here, integrated with scipy's Radau at rtol 1e-11.

Nothing here imports ecdsim (not even its chain kinematics): the panels' positions are
written out, the mass matrix ``M = sum m Jv^T Jv + I Jw^T Jw``, the Christoffel velocity
terms and the gravity forces ``-dV/dq`` are derived symbolically (Spong, Hutchinson and
Vidyasagar, *Robot Modeling and Control*, 2006, chapter 7) and lambdified, and every
hinge law is typed from its source:

- the spring, linear in the hinge's deployed angle (the paper's Eq. 7, extended beyond
  the travel for a compliant latch's overshoot);
- the ECD as a linear damper and a Coulomb friction at the hinge, BECD_T and FECD_T
  (Eq. 1-4, evaluated by the cases in plain floats), plus the hinge friction FS_T, with
  a breakaway (static) friction at rest;
- the damper's self-heating, typed from Incropera, DeWitt, Bergman and Lavine,
  *Fundamentals of Heat and Mass Transfer* (2007), sections 3.1.3 and 5.2, in
  temperatures (not ecdsim's log state): the rotor a lumped capacity heated by its
  eddy-current power ``BD_T(T_r) N^2 w^2`` (Eq. 1's damping at the rotor's temperature,
  linear in it), cooled to the environment or to a housing node of its own, which is
  cooled to the environment; a warm start gives both nodes a rise at release;
- with a Stribeck speed w_St, a hinge's sliding friction falls from its breakaway at rest
  to its kinetic value as it speeds up, ``F_C + (F_brk - F_C) exp(-(w / w_St)^2)`` (the
  steady-state Stribeck curve of the LuGre model, Canudas de Wit, Olsson, Astrom and
  Lischinsky, IEEE TAC 40(3), 1995, Eq. 4's g(v)), typed here;
- Coulomb friction with stick-slip at every hinge: the hinges at rest are decided
  together, exactly, by enumerating their modes (stuck, sliding either way) and keeping
  the one whose stuck hinges' holding torques, computed from M(q) with the stuck hinges'
  accelerations zero, are within their breakaway limits and whose sliding hinges
  accelerate the way they slide (with constant friction limits the problem is convex
  and its solution unique); events for a sliding hinge's speed reaching zero and for a
  stuck hinge's holding torque reaching its breakaway;
- latches as end stops: rigid, Newton's impact law ``v+ = -e v-`` applied to the chain by
  a generalised impulse (the latched and just-arriving hinges constrained, every other
  hinge free; a hinge resting on its stowed stop constrained only if pushed back), a
  latch with e = 0 locking its hinge; or compliant, a spring and damper holding the
  hinge both ways from its first arrival;
- closed cable loops between adjacent hinges: elastic, two pretensioned strands whose
  stiffness halves where one slackens (Hooke's law per strand), with events at the
  slack points; or rigid, the holonomic constraint ``phi_out = r phi_in`` eliminated by
  reduced coordinates (one coordinate per group of rigidly coupled hinges);
- gravity in a ground test, with the fraction of each panel's weight carried at its
  centre of gravity by the ground-support equipment;
- a lossy gear between a hinge and its damper (Modelica's LossyGear, Pelchen, Schweiger
  and Otter 2002): Newton's law for the damper side (its reflected inertia, damping and
  Coulomb friction) gives the torque the mesh passes, ``T = J_D phi'' + B phi' + F_G
  sign(phi')``; the hinge sees ``T / eta_f`` while T and the motion agree (the hinge
  drives the damper) and ``eta_b T`` while they oppose (the damper side drives the
  hinge). Each lossy hinge's flow is decided at every event by enumerating the flows of
  all of them and keeping the consistent one (T of each hinge's sign agreeing with its
  flow, under the accelerations of those flows), an event where a T passes zero; the
  mesh's loss ``(T / eta_f - T) |phi'|`` or ``(T - eta_b T) |phi'|`` is integrated;
- lost motion (backlash) in a rigid gear: until the hinge has turned through it from
  release the damper side idles (no rotor inertia, damping or ECD friction at the
  hinge); where it closes, the rotor at rest is caught by the moving chain in a plastic
  impact, momentum ``M_before phi'-`` conserved with the rotor's inertia added (seen
  through the gear driven forward, ``J_D / eta_f``), the kinetic energy lost booked.

Conventions as docs/wing.md: relative hinge angles q (q_1 from the base's x axis),
deployed angles phi = s (q - q_stowed) from 0 to each hinge's travel. Energy terms are
integrated with the motion, so the run's energy balance is a check of the reference
itself.
"""

from __future__ import annotations

import functools
import itertools
import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np
import numpy.typing as npt
import sympy as sp
from scipy.integrate import solve_ivp
from scipy.optimize import minimize_scalar

FloatArray = npt.NDArray[np.float64]

RTOL = 1e-11
ATOL = 1e-13
# A holding torque may exceed the breakaway by this fraction (rounding) and still hold: a
# motion that stops exactly where the drive equals the friction stays stopped.
STICK_MARGIN = 1e-12
# Rebounds whose kinetic energy falls below this fraction of the first arrival's are
# taken as settled against the latch (as ecdsim's single hinge does, docs/dynamics.md).
SETTLE_FRACTION = 1e-12


@dataclass(frozen=True)
class Panel:
    """A rigid panel: mass [kg], hinge-to-hinge length [m], centre of gravity along and
    across from its inboard hinge [m], inertia about the centre of gravity [kg*m^2]."""

    mass: float
    length: float
    cg_along: float
    cg_across: float
    inertia: float


@dataclass(frozen=True)
class Hinge:
    """A hinge's laws at one temperature, at the hinge (deployed angle phi).

    Attributes
    ----------
    stowed, deployed : relative angles q at release and at the latch [rad]
    start_torque, end_torque : the spring at phi = 0 and at the travel [N*m]
    damping : BECD_T [N*m*s/rad]
    friction : kinetic Coulomb friction FECD_T + FS_T [N*m]
    breakaway : static friction f_D FECD_T + f_S FS_T [N*m], >= friction
    inertia : the ECD's rotor and gear train reflected to the hinge, (J_r + J_g) N^2
        [kg*m^2], added to the hinge's diagonal of the mass matrix
    restitution : a rigid latch's e [-]
    latch_stiffness, latch_damping : a compliant latch [N*m/rad], [N*m*s/rad]; stiffness
        None for a rigid latch
    eddy_damping : the eddy-current part of ``damping``, BD_T N^2 at the ambient
        temperature [N*m*s/rad] (what heats the rotor)
    eddy_slope : its change per kelvin of the rotor, BD c N^2 [N*m*s/rad/K] (Eq. 1)
    heat_capacity : the rotor's C_r [J/K]; None: no heating
    thermal_resistance : the rotor's resistance to the environment, or to the housing
        with a housing node [K/W]
    housing_heat_capacity, housing_resistance : the housing node's C_h [J/K] (None: one
        node) and its resistance to the environment [K/W]
    initial_rotor_rise, initial_housing_rise : the nodes' rises at release [K]
    stribeck_speed : w_St [rad/s] at the hinge; inf: Coulomb friction (no Stribeck curve)
    forward_efficiency, backward_efficiency : a lossy gear's eta_f and eta_b [-] (1, 1:
        ideal); ``damping`` and ``friction`` are then through an ideal gear (BT N^2 and
        FS + FT N) and ``breakaway`` at eta_f (the hinge drives the damper from rest)
    gear_friction : the ECD's Coulomb friction through an ideal gear, FT N [N*m] (part
        of ``friction``; the share the mesh factor multiplies)
    lost_motion : the gear's backlash at the hinge [rad] (0: engaged from release)
    ecd_friction, ecd_breakaway : the ECD's shares of ``friction`` and ``breakaway``
        [N*m], which idle while the lost motion is open
    """

    stowed: float
    deployed: float
    start_torque: float
    end_torque: float
    damping: float = 0.0
    friction: float = 0.0
    breakaway: float = 0.0
    inertia: float = 0.0
    restitution: float = 0.0
    latch_stiffness: float | None = None
    latch_damping: float = 0.0
    eddy_damping: float = 0.0
    eddy_slope: float = 0.0
    heat_capacity: float | None = None
    thermal_resistance: float = math.inf
    housing_heat_capacity: float | None = None
    housing_resistance: float = math.inf
    initial_rotor_rise: float = 0.0
    initial_housing_rise: float = 0.0
    stribeck_speed: float = math.inf
    forward_efficiency: float = 1.0
    backward_efficiency: float = 1.0
    gear_friction: float = 0.0
    lost_motion: float = 0.0
    ecd_friction: float = 0.0
    ecd_breakaway: float = 0.0

    @property
    def lossy(self) -> bool:
        """A gear with an efficiency below 1 either way."""
        return self.forward_efficiency != 1.0 or self.backward_efficiency != 1.0

    def factor(self, flow: float) -> float:
        """What the hinge sees of the mesh's torque: 1/eta_f (flow > 0), eta_b (< 0), 1."""
        if flow > 0.0:
            return 1.0 / self.forward_efficiency
        if flow < 0.0:
            return self.backward_efficiency
        return 1.0

    def sliding(self, speed: float) -> float:
        """The sliding friction's magnitude at the hinge speed ``speed`` [N*m]:
        ``F_C + (F_brk - F_C) exp(-(w / w_St)^2)`` (Canudas de Wit et al. 1995), the
        kinetic friction without a Stribeck speed."""
        if math.isinf(self.stribeck_speed):
            return self.friction
        ratio = speed / self.stribeck_speed
        return self.friction + (self.breakaway - self.friction) * math.exp(-ratio * ratio)

    def heating(self, speed: float, rotor: float, housing: float) -> tuple[float, float]:
        """The rates of the rotor's and the housing's rises over the environment [K/s]:
        ``C_r r' = (BD_T(T_r) N^2) w^2 - (r - h) / R`` and
        ``C_h h' = (r - h) / R - h / R_he`` (h = 0 without a housing node; Incropera et
        al. 2007, Eq. 5.2 per node with the resistances of section 3.1.3)."""
        if self.heat_capacity is None:
            return 0.0, 0.0
        eddy = self.eddy_damping + self.eddy_slope * rotor
        if self.housing_heat_capacity is None:
            loss = rotor / self.thermal_resistance
            return (eddy * speed * speed - loss) / self.heat_capacity, 0.0
        flow = (rotor - housing) / self.thermal_resistance
        return (
            (eddy * speed * speed - flow) / self.heat_capacity,
            (flow - housing / self.housing_resistance) / self.housing_heat_capacity,
        )

    def damping_at(self, rotor: float) -> float:
        """BECD_T with the rotor ``rotor`` kelvin above the environment [N*m*s/rad]
        (Eq. 1 is linear in the temperature)."""
        return self.damping + self.eddy_slope * rotor

    @property
    def travel(self) -> float:
        """|deployed - stowed| [rad]."""
        return abs(self.deployed - self.stowed)

    @property
    def direction(self) -> float:
        """s: +1 where q grows as the hinge deploys."""
        return 1.0 if self.deployed > self.stowed else -1.0

    def spring(self, phi: float) -> float:
        """Eq. 7 at the deployed angle phi [N*m]."""
        return self.start_torque + (self.end_torque - self.start_torque) * phi / self.travel

    def spring_work(self, phi: float) -> float:
        """Work of the spring from 0 to phi [J], the integral of Eq. 7."""
        slope = (self.end_torque - self.start_torque) / self.travel
        return self.start_torque * phi + 0.5 * slope * phi * phi


@dataclass(frozen=True)
class Cable:
    """A closed cable loop holding phi[inboard + 1] = ratio phi[inboard]: rigid without a
    stiffness, else with the loop's stiffness K [N*m/rad] and slack torque [N*m]."""

    inboard: int
    ratio: float
    stiffness: float | None = None
    slack_torque: float = 0.0

    def torque(self, delta: float) -> float:
        """Torque on the outboard hinge at delta = phi_out - r phi_in [N*m]."""
        assert self.stiffness is not None
        k, limit = self.stiffness, self.slack_torque / self.stiffness
        if abs(delta) <= limit:
            return -k * delta
        return -math.copysign(0.5 * (self.slack_torque + k * abs(delta)), delta)

    def energy(self, delta: float) -> float:
        """Elastic energy at delta [J] (the integral of -torque)."""
        assert self.stiffness is not None
        k, limit = self.stiffness, self.slack_torque / self.stiffness
        if abs(delta) <= limit:
            return 0.5 * k * delta * delta
        d = abs(delta)
        return (
            0.5 * k * limit**2
            + 0.5 * self.slack_torque * (d - limit)
            + 0.25 * k * (d * d - limit**2)
        )


@dataclass(frozen=True)
class Wing:
    """Panels and hinges root first, cables, gravity (x, y) [m/s^2] and offloads."""

    panels: tuple[Panel, ...]
    hinges: tuple[Hinge, ...]
    cables: tuple[Cable, ...] = ()
    gravity: tuple[float, float] = (0.0, 0.0)
    offload: tuple[float, ...] | None = None

    @property
    def size(self) -> int:
        """The number of panels."""
        return len(self.panels)


@dataclass(frozen=True)
class _Chain:
    mass_matrix: Callable[..., Any]
    velocity: Callable[..., Any]
    gravity: Callable[..., Any]
    potential: Callable[..., Any]


@functools.cache
def derive_chain(n: int) -> _Chain:
    """M(q), h(q, q'), Q_g(q) and V_g(q) of an n-panel chain, derived with sympy.

    Each panel's centre of gravity is written out (``c_i = p_i + a_i e_i + b_i n_i``,
    ``p_{i+1} = p_i + L_i e_i``, absolute angle ``q_1 + ... + q_i``); then
    ``M = sum_i m_i Jv_i^T Jv_i + I_i Jw_i^T Jw_i``, ``h_k = sum_ij c_ijk q_i' q_j'`` with
    the Christoffel symbols ``c_ijk = (dM_kj/dq_i + dM_ki/dq_j - dM_ij/dq_k) / 2`` and
    ``Q = -dV/dq`` with ``V = -sum_i m_i (1 - o_i) g . c_i`` (Spong et al. 2006, 7.3-7.4).
    """
    q = sp.symbols(f"q0:{n}")
    dq = sp.symbols(f"dq0:{n}")
    m = sp.symbols(f"m0:{n}")
    a = sp.symbols(f"a0:{n}")
    b = sp.symbols(f"b0:{n}")
    inertia = sp.symbols(f"I0:{n}")
    length = sp.symbols(f"L0:{n}")
    offload = sp.symbols(f"o0:{n}")
    gx, gy = sp.symbols("gx gy")
    x: Any = sp.Integer(0)
    y: Any = sp.Integer(0)
    theta: Any = sp.Integer(0)
    matrix = sp.zeros(n, n)
    potential: Any = sp.Integer(0)
    for i in range(n):
        theta = theta + q[i]
        cx = x + a[i] * sp.cos(theta) - b[i] * sp.sin(theta)
        cy = y + a[i] * sp.sin(theta) + b[i] * sp.cos(theta)
        jv = sp.Matrix([cx, cy]).jacobian(sp.Matrix(q))
        jw = sp.Matrix([[1 if j <= i else 0 for j in range(n)]])
        matrix += m[i] * jv.T * jv + inertia[i] * jw.T * jw
        potential += -m[i] * (1 - offload[i]) * (gx * cx + gy * cy)
        x = x + length[i] * sp.cos(theta)
        y = y + length[i] * sp.sin(theta)
    velocity = []
    for k in range(n):
        term: Any = sp.Integer(0)
        for i in range(n):
            for j in range(n):
                christoffel = (
                    sp.diff(matrix[k, j], q[i])
                    + sp.diff(matrix[k, i], q[j])
                    - sp.diff(matrix[i, j], q[k])
                ) / 2
                term += christoffel * dq[i] * dq[j]
        velocity.append(term)
    gravity = [-sp.diff(potential, q[k]) for k in range(n)]
    args = (q, dq, m, a, b, inertia, length, offload, gx, gy)
    return _Chain(
        mass_matrix=sp.lambdify(args, matrix.tolist(), "math"),
        velocity=sp.lambdify(args, velocity, "math"),
        gravity=sp.lambdify(args, gravity, "math"),
        potential=sp.lambdify(args, potential, "math"),
    )


@dataclass
class Latching:
    """One hinge's latching as the reference records it."""

    hinge: int
    time: float
    speed: float
    kinetic_energy: float
    impact_loss: float = 0.0
    impulse: float | None = None
    peak_torque: float | None = None


@dataclass
class Segment:
    """One smooth piece of the motion: its time span and its dense output."""

    start: float
    end: float
    state: Callable[[float], tuple[FloatArray, FloatArray]]


@dataclass
class Solution:
    """The reference's answer: motion, events, latches, energy, how it ended."""

    wing: Wing
    segments: list[Segment] = field(default_factory=list)
    events: list[tuple[float, str, int | None]] = field(default_factory=list)
    latches: list[Latching] = field(default_factory=list)
    status: str = ""
    final_time: float = 0.0
    final_angle: FloatArray = field(default_factory=lambda: np.zeros(0))
    final_speed: FloatArray = field(default_factory=lambda: np.zeros(0))
    stuck_hinges: tuple[int, ...] = ()
    damper: FloatArray = field(default_factory=lambda: np.zeros(0))
    friction: FloatArray = field(default_factory=lambda: np.zeros(0))
    latch_damping: FloatArray = field(default_factory=lambda: np.zeros(0))
    impact_loss: FloatArray = field(default_factory=lambda: np.zeros(0))
    spring_work: FloatArray = field(default_factory=lambda: np.zeros(0))
    gravity_work: float = 0.0
    final_kinetic: float = 0.0
    cable_elastic: float = 0.0
    latch_elastic: float = 0.0
    peak_rise: FloatArray = field(default_factory=lambda: np.zeros(0))  # rotors' [K]
    gear_loss: FloatArray = field(default_factory=lambda: np.zeros(0))  # lossy meshes' [J]
    engagement_loss: FloatArray = field(default_factory=lambda: np.zeros(0))  # [J]

    @property
    def deployment_time(self) -> float:
        """When the last hinge first reached its deployed angle [s]; inf if one never did."""
        if len({latch.hinge for latch in self.latches}) < self.wing.size:
            return math.inf
        return max(latch.time for latch in self.latches)

    def sample(self, times: Sequence[float]) -> tuple[FloatArray, FloatArray]:
        """Deployed angles and speeds at ``times`` (within the run), shape (len, n)."""
        angles = np.empty((len(times), self.wing.size))
        speeds = np.empty_like(angles)
        for k, t in enumerate(times):
            for segment in self.segments:
                if segment.start <= t <= segment.end:
                    angles[k], speeds[k] = segment.state(t)
                    break
            else:
                angles[k], speeds[k] = self.final_angle, self.final_speed
        return angles, speeds

    @property
    def supplied(self) -> float:
        """Spring and gravity work (the wing starts at rest) [J]."""
        return float(np.sum(self.spring_work)) + self.gravity_work

    @property
    def accounted(self) -> float:
        """Dissipations, impact losses, final kinetic and elastic energies [J]."""
        return (
            float(
                np.sum(self.damper)
                + np.sum(self.friction)
                + np.sum(self.latch_damping)
                + np.sum(self.impact_loss)
                + np.sum(self.gear_loss)
                + np.sum(self.engagement_loss)
            )
            + self.final_kinetic
            + self.cable_elastic
            + self.latch_elastic
        )

    @property
    def energy_error(self) -> float:
        """|supplied - accounted| over the supplied energy [-]."""
        return abs(self.supplied - self.accounted) / max(abs(self.supplied), 1e-300)


class _Model:
    """The wing's equations in reduced coordinates psi (one per rigidly coupled group)."""

    def __init__(self, wing: Wing) -> None:
        self.wing = wing
        n = wing.size
        self.n = n
        self.chain = derive_chain(n)
        p = wing.panels
        self.params = (
            [x.mass for x in p],
            [x.cg_along for x in p],
            [x.cg_across for x in p],
            [x.inertia for x in p],
            [x.length for x in p],
            list(wing.offload) if wing.offload is not None else [0.0] * n,
            wing.gravity[0],
            wing.gravity[1],
        )
        self.stowed = np.array([h.stowed for h in wing.hinges])
        self.sign = np.array([h.direction for h in wing.hinges])
        self.travel = np.array([h.travel for h in wing.hinges])
        self.reflected = np.array([h.inertia for h in wing.hinges])
        # Groups of hinges joined by rigid cables: phi = P psi.
        group_of = list(range(n))
        factor = np.ones(n)
        for cable in sorted(wing.cables, key=lambda c: c.inboard):
            if cable.stiffness is None:
                group_of[cable.inboard + 1] = group_of[cable.inboard]
                factor[cable.inboard + 1] = factor[cable.inboard] * cable.ratio
        roots = sorted(set(group_of))
        self.groups = [[j for j in range(n) if group_of[j] == r] for r in roots]
        self.group_of = [roots.index(group_of[j]) for j in range(n)]
        self.m = len(roots)
        self.P = np.zeros((n, self.m))
        for j in range(n):
            self.P[j, self.group_of[j]] = factor[j]
        self.elastic = [c for c in wing.cables if c.stiffness is not None]
        for group in self.groups:
            first = wing.hinges[group[0]]
            for j in group:
                h = wing.hinges[j]
                assert abs(h.travel - self.P[j, self.group_of[j]] * first.travel) < 1e-9, (
                    "a rigid cable needs travels in its ratio"
                )
                assert (h.latch_stiffness is None) == (first.latch_stiffness is None)
        # Friction limits and travel of each group in psi.
        self.friction = self.P.T @ np.array([h.friction for h in wing.hinges])
        self.breakaway = self.P.T @ np.array([h.breakaway for h in wing.hinges])
        self.group_travel = np.array([self.travel[g[0]] for g in self.groups])
        self.rigid_latch = [wing.hinges[g[0]].latch_stiffness is None for g in self.groups]
        # The rotors' rises over the environment [K], set from the state being evaluated.
        self.rise = np.array([h.initial_rotor_rise for h in wing.hinges])
        # Each hinge's mesh factor in the current flows (1: ideal, or none decided).
        self.mesh = np.ones(n)
        # 1.0 where the hinge's damper side is engaged (its lost motion closed), else 0.0.
        self.meshed = np.array([0.0 if h.lost_motion > 0.0 else 1.0 for h in wing.hinges])

    def phi(self, psi: FloatArray) -> FloatArray:
        return np.asarray(self.P @ psi, dtype=float)

    def sliding_friction(self, rate: FloatArray) -> FloatArray:
        """Each group's sliding friction limit in psi at the groups' speeds ``rate``:
        ``P^T`` of each hinge's (its Stribeck curve at its speed; the breakaway at rest),
        its gear friction seen through its lossy mesh."""
        dphi = self.P @ rate
        each = np.array(
            [
                h.sliding(float(dphi[j]))
                + (self.mesh[j] - 1.0) * h.gear_friction
                - (1.0 - self.meshed[j]) * h.ecd_friction
                for j, h in enumerate(self.wing.hinges)
            ]
        )
        return np.asarray(self.P.T @ each, dtype=float)

    def matrices(
        self, psi: FloatArray, rate: FloatArray, lossy: bool = False
    ) -> tuple[FloatArray, FloatArray]:
        """M_psi and h_psi (Coriolis, centrifugal) at psi, psi'; with ``lossy`` each
        rotor's inertia as the hinge sees it through its lossy mesh."""
        phi, dphi = self.P @ psi, self.P @ rate
        q = self.stowed + self.sign * phi
        dq = self.sign * dphi
        mq = np.array(self.chain.mass_matrix(q, dq, *self.params), dtype=float)
        hq = np.array(self.chain.velocity(q, dq, *self.params), dtype=float)
        s = np.diag(self.sign)
        rotors = self.reflected * self.meshed * (self.mesh if lossy else 1.0)
        m_phi = s @ mq @ s + np.diag(rotors)
        h_phi = self.sign * hq
        return self.P.T @ m_phi @ self.P, self.P.T @ h_phi

    def mesh_torques(self, rate: FloatArray, acc: FloatArray, direction: FloatArray) -> FloatArray:
        """Each sliding hinge's mesh torque along its motion, the damper side's Newton's
        law ``d (J_D phi'' + B phi') + F_G`` through an ideal gear [N*m] (0 at rest)."""
        dphi, ddphi = self.P @ rate, self.P @ acc
        torques = np.zeros(self.n)
        for j, h in enumerate(self.wing.hinges):
            d = direction[self.group_of[j]]
            if d != 0.0:
                own = h.inertia * ddphi[j] + h.damping_at(self.rise[j]) * dphi[j]
                torques[j] = d * own + h.gear_friction
        return torques

    def breakaways(self) -> FloatArray:
        """Each group's breakaway limit in psi (an open lost motion's ECD idles)."""
        each = [
            h.breakaway - (1.0 - self.meshed[j]) * h.ecd_breakaway
            for j, h in enumerate(self.wing.hinges)
        ]
        return np.asarray(self.P.T @ np.array(each), dtype=float)

    def kinetic(self, psi: FloatArray, rate: FloatArray) -> float:
        m, _ = self.matrices(psi, np.zeros_like(rate))
        return 0.5 * float(rate @ m @ rate)

    def gravity_potential(self, psi: FloatArray) -> float:
        q = self.stowed + self.sign * (self.P @ psi)
        return float(self.chain.potential(q, np.zeros(self.n), *self.params))

    def smooth_forces(
        self, psi: FloatArray, rate: FloatArray, engaged: Sequence[bool]
    ) -> FloatArray:
        """Generalised forces on phi of everything but friction: springs, ECD damping,
        engaged compliant latches, elastic cables, gravity [N*m]."""
        phi, dphi = self.P @ psi, self.P @ rate
        forces = np.empty(self.n)
        for j, h in enumerate(self.wing.hinges):
            damping = self.mesh[j] * self.meshed[j] * h.damping_at(self.rise[j])
            forces[j] = h.spring(phi[j]) - damping * dphi[j]
            if engaged[j]:
                assert h.latch_stiffness is not None
                forces[j] -= h.latch_stiffness * (phi[j] - h.travel) + h.latch_damping * dphi[j]
        for c in self.elastic:
            torque = c.torque(phi[c.inboard + 1] - c.ratio * phi[c.inboard])
            forces[c.inboard + 1] += torque
            forces[c.inboard] -= c.ratio * torque
        q = self.stowed + self.sign * phi
        forces += self.sign * np.array(
            self.chain.gravity(q, np.zeros(self.n), *self.params), dtype=float
        )
        return forces

    def accelerations(
        self,
        psi: FloatArray,
        rate: FloatArray,
        engaged: Sequence[bool],
        held: Sequence[bool],
        sliding: FloatArray,
        limits: FloatArray,
    ) -> tuple[FloatArray, FloatArray]:
        """psi'' with the held groups' accelerations zero, and the held groups' holding
        torques lambda (what friction or the latch must supply).

        ``sliding[g]`` is the direction of group g's friction (0 for a held group), with
        magnitude ``limits[g]``.
        """
        m, h = self.matrices(psi, rate, lossy=True)
        force = self.P.T @ self.smooth_forces(psi, rate, engaged) - sliding * limits
        free = [g for g in range(self.m) if not held[g]]
        hold = [g for g in range(self.m) if held[g]]
        acc = np.zeros(self.m)
        if free:
            acc[free] = np.linalg.solve(m[np.ix_(free, free)], (force - h)[free])
        holding = np.zeros(self.m)
        if hold:
            holding[hold] = (m @ acc + h - force)[hold]
        return acc, holding


@dataclass
class _Mode:
    """Which groups are locked (latched rigidly), stuck or sliding (with direction)."""

    locked: list[bool]
    stuck: list[bool]
    direction: FloatArray  # +1 / -1 for sliding groups, 0 for held ones
    engaged: list[bool]  # per hinge: compliant latch engaged
    flow: list[float] = field(default_factory=list)  # per hinge: lossy gear +1 / -1 / 0

    @property
    def held(self) -> list[bool]:
        return [a or b for a, b in zip(self.locked, self.stuck, strict=True)]


class Reference:
    """Integrate one wing from release: ``Reference(wing).run(stop_time)``."""

    def __init__(self, wing: Wing, max_events: int = 2000) -> None:
        self.model = _Model(wing)
        self.wing = wing
        self.max_events = max_events
        n = wing.size
        # The nodes' rises (rotors, then housings) carried from segment to segment [K],
        # and the rotors' largest so far.
        self.thermal = np.zeros(2 * n)
        self.peak_rise = np.zeros(n)

    # ------------------------------------------------------------------ decisions
    def _flows(
        self, psi: FloatArray, rate: FloatArray, mode: _Mode, switched: tuple[int, float] | None
    ) -> None:
        """Every lossy gear's power flow, decided together: each combination of the
        sliding lossy hinges' flows is tried, and one whose mesh torques (under its own
        accelerations) agree in sign with its flows kept, the one changing fewest flows;
        ``switched`` (a hinge whose torque has just passed zero, and its new flow) fixes
        that hinge's flow."""
        model = self.model
        lossy = [
            j
            for j, h in enumerate(self.wing.hinges)
            if h.lossy and model.meshed[j] and mode.direction[model.group_of[j]] != 0.0
        ]
        flow = [0.0] * model.n
        best: tuple[int, list[float]] | None = None
        for combo in itertools.product((1.0, -1.0), repeat=len(lossy)):
            for j, value in zip(lossy, combo, strict=True):
                flow[j] = value
            if switched is not None and switched[0] in lossy and flow[switched[0]] != switched[1]:
                continue
            model.mesh = np.array([h.factor(flow[j]) for j, h in enumerate(self.wing.hinges)])
            acc, _ = model.accelerations(
                psi, rate, mode.engaged, mode.held, mode.direction, model.sliding_friction(rate)
            )
            torques = model.mesh_torques(rate, acc, mode.direction)
            agree = all(
                torques[j] * flow[j] >= 0.0 for j in lossy if switched is None or j != switched[0]
            )
            kept = sum(flow[j] == (mode.flow[j] if mode.flow else 0.0) for j in lossy)
            if agree and (best is None or kept > best[0]):
                best = (kept, list(flow))
        if best is None:
            raise RuntimeError("no consistent power flow of the lossy gears")
        mode.flow = best[1]
        model.mesh = np.array([h.factor(mode.flow[j]) for j, h in enumerate(self.wing.hinges)])

    def _decide(
        self, psi: FloatArray, rate: FloatArray, mode: _Mode, moving: int | None = None
    ) -> None:
        """Stick or slide, for every unlocked group at rest, decided together.

        ``moving``: a group whose holding torque has just grown through its breakaway (a
        breakaway event): at that instant it is exactly at its limit, where holding and
        sliding are both consistent, and the growing torque makes it slide.
        """
        model = self.model
        rest = [g for g in range(model.m) if not mode.locked[g] and rate[g] == 0.0]
        if not rest:
            return
        choices: list[list[str]] = []
        for g in rest:
            at_stop = psi[g] == 0.0
            options = ["stuck", "+"] if at_stop else ["stuck", "+", "-"]
            choices.append(options[1:] if g == moving else options)
        consistent = []
        for combo in itertools.product(*choices):
            stuck = list(mode.locked)
            direction = np.array(mode.direction, dtype=float)
            for g, choice in zip(rest, combo, strict=True):
                stuck[g] = choice == "stuck"
                direction[g] = 0.0 if choice == "stuck" else (1.0 if choice == "+" else -1.0)
            held = [a or b for a, b in zip(stuck, mode.locked, strict=True)]
            # A stuck group holds up to its breakaway; a sliding one feels the kinetic
            # friction at once (it drops from breakaway to kinetic as motion starts).
            acc, holding = model.accelerations(
                psi, rate, mode.engaged, held, direction, model.sliding_friction(rate)
            )
            ok = True
            for g, choice in zip(rest, combo, strict=True):
                limit = model.breakaways()[g] * (1.0 + STICK_MARGIN)
                if choice == "stuck":
                    low = -limit
                    high = math.inf if psi[g] == 0.0 else limit
                    ok &= low <= holding[g] <= high
                else:
                    ok &= direction[g] * acc[g] > 0.0
            if ok:
                consistent.append((sum(c == "stuck" for c in combo), combo, direction, stuck))
        if not consistent and moving is not None:
            # The breakaway was a touch, not a crossing: it holds.
            self._decide(psi, rate, mode)
            return
        if not consistent:
            raise RuntimeError(f"no consistent stick-slip mode at rest (groups {rest})")
        # With breakaway equal to kinetic friction the problem is convex and its answer
        # unique. With a higher breakaway several modes can be consistent (Coulomb's law
        # with stiction is not unique): the friction holds whatever it can, so the mode
        # that keeps the most groups stuck is taken (at a boundary too).
        consistent.sort(key=lambda item: -item[0])
        _, _, direction, stuck = consistent[0]
        mode.direction = direction
        mode.stuck = [s and not lk for s, lk in zip(stuck, mode.locked, strict=True)]

    def _impact(
        self, psi: FloatArray, rate: FloatArray, mode: _Mode, group: int, target: float
    ) -> tuple[FloatArray, float]:
        """A generalised impulse setting group's speed to ``target``; latched groups stay
        at rest; a group resting on its stowed stop is held only if pushed back."""
        m, _ = self.model.matrices(psi, rate)
        inverse = np.linalg.inv(m)
        constrained = {g: 0.0 for g in range(self.model.m) if mode.locked[g]}
        constrained[group] = target
        while True:
            keys = sorted(constrained)
            e = np.zeros((self.model.m, len(keys)))
            for col, g in enumerate(keys):
                e[g, col] = 1.0
            wanted = np.array([constrained[g] for g in keys]) - e.T @ rate
            impulse = np.linalg.solve(e.T @ inverse @ e, wanted)
            after = rate + inverse @ e @ impulse
            pushed = [
                g
                for g in range(self.model.m)
                if g not in constrained and psi[g] == 0.0 and after[g] < 0.0
            ]
            if not pushed:
                break
            for g in pushed:
                constrained[g] = 0.0
        for g in keys:
            after[g] = constrained[g]
        return after, float(impulse[keys.index(group)])

    def _engage(
        self, psi: FloatArray, rate: FloatArray, mode: _Mode, j: int, losses: FloatArray
    ) -> FloatArray:
        """Hinge j's lost motion closes: its rotor, at rest, is caught in a plastic impact
        (generalised momentum conserved over the unlocked groups, the rotor added through
        the gear driven forward); returns the speeds after, sets the modes."""
        model = self.model
        g = model.group_of[j]
        hinge = self.wing.hinges[j]
        psi[g] = hinge.lost_motion / model.P[j, g]
        before = model.kinetic(psi, rate)
        m_before, _ = model.matrices(psi, np.zeros(model.m))
        momentum = m_before @ rate
        model.meshed[j] = 1.0
        m_after, _ = model.matrices(psi, np.zeros(model.m))
        m_after[g, g] += model.P[j, g] ** 2 * hinge.inertia / hinge.forward_efficiency
        m_after[g, g] -= model.P[j, g] ** 2 * hinge.inertia  # (the ideal share is in M)
        free = [k for k in range(model.m) if not mode.locked[k]]
        after = rate.copy()
        after[free] = np.linalg.solve(m_after[np.ix_(free, free)], momentum[free])
        losses[j] += before - model.kinetic(psi, after)
        for k in free:
            mode.stuck[k] = False
            mode.direction[k] = 0.0 if after[k] == 0.0 else math.copysign(1.0, after[k])
        return after

    # ------------------------------------------------------------------ the run
    def run(self, stop_time: float = math.inf) -> Solution:
        """Integrate from release (rest, stowed) to the end; see :class:`Solution`."""
        model = self.model
        wing = self.wing
        n, m = model.n, model.m
        psi = np.zeros(m)
        rate = np.zeros(m)
        mode = _Mode([False] * m, [False] * m, np.zeros(m), [False] * n, [0.0] * n)
        switched: tuple[int, float] | None = None
        out = Solution(wing)
        out.events.append((0.0, "release", None))
        energy = {
            "damper": np.zeros(n),
            "friction": np.zeros(n),
            "latch": np.zeros(n),
            "gear": np.zeros(n),
        }
        impact_loss = np.zeros(n)
        engagement = np.zeros(n)
        first_arrival: dict[int, Latching] = {}
        arrival_kinetic: dict[int, float] = {}
        peak: dict[int, float] = {}
        v0 = model.gravity_potential(psi)
        t = 0.0
        self.thermal = np.array(
            [h.initial_rotor_rise for h in wing.hinges]
            + [h.initial_housing_rise for h in wing.hinges]
        )
        model.rise = self.thermal[:n].copy()
        self.peak_rise = self.thermal[:n].copy()
        self._decide(psi, rate, mode)
        for _ in range(self.max_events):
            if all(mode.locked) or all(mode.held) or t >= stop_time:
                break
            self._flows(psi, rate, mode, switched)
            switched = None
            t, psi, rate, kind, group = self._segment(
                t, psi, rate, mode, stop_time, out, energy, peak
            )
            if kind == "stop_time":
                out.events.append((t, "stop_time", None))
                break
            if kind == "power_flow":
                assert group is not None  # here: the hinge
                switched = (group, -mode.flow[group])
                out.events.append((t, "power_flow", group))
                continue
            if kind == "gear_engage":
                assert group is not None  # here: the hinge
                rate = self._engage(psi, rate, mode, group, engagement)
                out.events.append((t, "gear_engage", group))
                self._decide(psi, rate, mode)
                continue
            hinge = model.groups[group][0] if group is not None else None
            if kind == "zero_speed":
                assert group is not None
                rate[group] = 0.0
                out.events.append((t, "zero_speed", hinge))
                mode.direction[group] = 0.0
                self._decide(psi, rate, mode)
                out.events.append((t, "stick" if mode.stuck[group] else "breakaway", hinge))
            elif kind == "breakaway":
                assert group is not None
                mode.stuck[group] = False
                self._decide(psi, rate, mode, moving=group)
                out.events.append((t, "breakaway" if not mode.stuck[group] else "stick", hinge))
            elif kind == "latch_rigid":
                assert group is not None
                assert hinge is not None
                psi[group] = model.group_travel[group]
                speed = float(rate[group] * model.P[hinge, group])
                before = model.kinetic(psi, rate)
                e = wing.hinges[hinge].restitution
                first = group not in first_arrival
                if first:
                    arrival_kinetic[group] = before
                after, impulse = self._impact(psi, rate, mode, group, -e * rate[group])
                m_after = model.kinetic(psi, after)
                settled = False
                if e > 0.0:
                    mm, _ = model.matrices(psi, after)
                    free = [g for g in range(m) if not mode.locked[g]]
                    inv = np.linalg.inv(mm[np.ix_(free, free)])
                    effective = 1.0 / inv[free.index(group), free.index(group)]
                    rebound = 0.5 * effective * after[group] ** 2
                    if rebound < SETTLE_FRACTION * arrival_kinetic[group]:
                        after, _ = self._impact(psi, rate, mode, group, 0.0)
                        m_after = model.kinetic(psi, after)
                        settled = True
                impact_loss[hinge] += before - m_after
                if first:
                    latch = Latching(hinge, t, speed, before, impulse=impulse)
                    first_arrival[group] = latch
                    out.latches.append(latch)
                    # The other hinges of a rigidly coupled group arrive with it; how the
                    # group's impulse divides between their latches is indeterminate.
                    for j in model.groups[group][1:]:
                        out.latches.append(
                            Latching(j, t, float(rate[group] * model.P[j, group]), before)
                        )
                first_arrival[group].impact_loss += before - m_after
                rate = after
                if e == 0.0 or settled:
                    mode.locked[group] = True
                    mode.stuck[group] = False
                    mode.direction[group] = 0.0
                    rate[group] = 0.0
                    for j in model.groups[group]:
                        out.events.append((t, "latch" if e == 0.0 else "settle", j))
                else:
                    out.events.append((t, "rebound", hinge))
                for g in range(m):
                    if not mode.locked[g] and rate[g] != 0.0:
                        mode.stuck[g] = False
                        mode.direction[g] = math.copysign(1.0, rate[g])
                    elif not mode.locked[g]:
                        mode.direction[g] = 0.0
                self._decide(psi, rate, mode)
            elif kind == "latch_engage":
                assert hinge is not None
                assert group is not None
                psi[group] = model.group_travel[group]
                for j in model.groups[group]:
                    mode.engaged[j] = True
                latch = Latching(
                    hinge, t, float(rate[group] * model.P[hinge, group]), model.kinetic(psi, rate)
                )
                first_arrival[group] = latch
                peak[hinge] = 0.0
                out.latches.append(latch)
                out.events.append((t, "latch_engage", hinge))
            elif kind == "start_stop":
                assert group is not None
                psi[group] = 0.0
                before = model.kinetic(psi, rate)
                rate, _ = self._impact(psi, rate, mode, group, 0.0)
                impact_loss[hinge] += before - model.kinetic(psi, rate)
                rate[group] = 0.0
                mode.direction[group] = 0.0
                out.events.append((t, "start_stop", hinge))
                self._decide(psi, rate, mode)
            elif kind in ("slack", "taut"):
                out.events.append((t, kind, None))
        else:
            raise RuntimeError("the reference's event limit")
        for j in peak:
            first_arrival[model.group_of[j]].peak_torque = peak[j]
        phi = model.phi(psi)
        out.final_time = t
        out.final_angle = phi
        out.final_speed = model.P @ rate
        if all(mode.locked) or (
            all(mode.held)
            and all(mode.locked[model.group_of[j]] or mode.engaged[j] for j in range(n))
        ):
            out.status = "latched"
        elif all(mode.held):
            out.status = "stuck"
        else:
            out.status = "stop_time"
        out.stuck_hinges = tuple(
            j for j in range(n) if mode.stuck[model.group_of[j]] and not mode.engaged[j]
        )
        out.peak_rise = self.peak_rise.copy()
        out.damper = energy["damper"]
        out.friction = energy["friction"]
        out.latch_damping = energy["latch"]
        out.gear_loss = energy["gear"]
        out.engagement_loss = engagement
        out.impact_loss = impact_loss
        out.spring_work = np.array([h.spring_work(phi[j]) for j, h in enumerate(wing.hinges)])
        out.gravity_work = v0 - model.gravity_potential(psi)
        out.final_kinetic = model.kinetic(psi, rate)
        out.cable_elastic = sum(
            c.energy(phi[c.inboard + 1] - c.ratio * phi[c.inboard]) for c in model.elastic
        )
        out.latch_elastic = sum(
            0.5 * h.latch_stiffness * (phi[j] - h.travel) ** 2
            for j, h in enumerate(wing.hinges)
            if mode.engaged[j] and h.latch_stiffness is not None
        )
        return out

    def _segment(
        self,
        t0: float,
        psi0: FloatArray,
        rate0: FloatArray,
        mode: _Mode,
        stop_time: float,
        out: Solution,
        energy: dict[str, FloatArray],
        peak: dict[int, float],
    ) -> tuple[float, FloatArray, FloatArray, str, int | None]:
        """Integrate one smooth piece to its first event; return the state there."""
        model = self.model
        n, m = model.n, model.m
        held = mode.held
        free = [g for g in range(m) if not held[g]]
        f = len(free)
        engaged = list(mode.engaged)
        direction = mode.direction.copy()

        def unpack(y: FloatArray) -> tuple[FloatArray, FloatArray]:
            psi = psi0.copy()
            rate = np.zeros(m)
            psi[free] = y[:f]
            rate[free] = y[f : 2 * f]
            model.rise = y[2 * f : 2 * f + n].copy()  # the rotors' rises: the damping
            return psi, rate

        def rhs(_t: float, y: FloatArray) -> FloatArray:
            psi, rate = unpack(y)
            limits = model.sliding_friction(rate)
            acc, _ = model.accelerations(psi, rate, engaged, held, direction, limits)
            dphi = model.P @ rate
            sliding = np.abs(model.P @ direction)
            hinges = self.wing.hinges
            damping = np.array([h.damping_at(model.rise[j]) for j, h in enumerate(hinges)])
            heat = np.array(
                [
                    h.heating(model.meshed[j] * dphi[j], y[2 * f + j], y[2 * f + n + j])
                    for j, h in enumerate(self.wing.hinges)
                ]
            )
            friction = np.array(
                [
                    h.sliding(float(dphi[j])) - (1.0 - model.meshed[j]) * h.ecd_friction
                    for j, h in enumerate(hinges)
                ]
            )
            latch = np.array(
                [h.latch_damping if engaged[j] else 0.0 for j, h in enumerate(self.wing.hinges)]
            )
            torques = model.mesh_torques(rate, acc, direction)
            gear = (model.mesh - 1.0) * torques * np.abs(dphi)
            return np.concatenate(
                [
                    rate[free],
                    acc[free],
                    heat[:, 0],
                    heat[:, 1],
                    model.meshed * damping * dphi**2,
                    np.where(sliding > 0.0, friction * np.abs(dphi), 0.0),
                    latch * dphi**2,
                    gear,
                ]
            )

        events: list[Callable[[float, FloatArray], float]] = []
        meaning: list[tuple[str, int | None]] = []

        def add(
            function: Callable[[float, FloatArray], float],
            direction_: float,
            kind: str,
            group: int | None,
        ) -> None:
            function.terminal = True  # type: ignore[attr-defined]
            function.direction = direction_  # type: ignore[attr-defined]
            events.append(function)
            meaning.append((kind, group))

        def speed_of(k: int, sign: float) -> Callable[[float, FloatArray], float]:
            return lambda _t, y: float(sign * y[f + k])

        def angle_of(k: int, offset: float) -> Callable[[float, FloatArray], float]:
            return lambda _t, y: float(y[k] - offset)

        def holding_margin(g: int) -> Callable[[float, FloatArray], float]:
            def margin(_t: float, y: FloatArray) -> float:
                psi, rate = unpack(y)
                _, holding = model.accelerations(
                    psi, rate, engaged, held, direction, model.sliding_friction(rate)
                )
                limit = model.breakaways()[g] * (1.0 + STICK_MARGIN)
                if psi0[g] == 0.0:
                    return float(holding[g] + limit)  # the stowed stop holds a push back
                return float(limit - abs(holding[g]))

            return margin

        def deflection_from(cable: Cable, slack: float) -> Callable[[float, FloatArray], float]:
            def deflection(_t: float, y: FloatArray) -> float:
                psi, _ = unpack(y)
                phi = model.P @ psi
                return float(phi[cable.inboard + 1] - cable.ratio * phi[cable.inboard] - slack)

            return deflection

        for g in free:
            k = free.index(g)
            add(speed_of(k, direction[g]), -1.0, "zero_speed", g)
            if direction[g] < 0.0:
                add(angle_of(k, 0.0), -1.0, "start_stop", g)
            if model.rigid_latch[g]:
                add(angle_of(k, model.group_travel[g]), 1.0, "latch_rigid", g)
            elif not engaged[model.groups[g][0]]:
                add(angle_of(k, model.group_travel[g]), 1.0, "latch_engage", g)
        for g in range(m):
            if mode.stuck[g]:
                add(holding_margin(g), -1.0, "breakaway", g)
        for cable in model.elastic:
            assert cable.stiffness is not None
            limit = cable.slack_torque / cable.stiffness
            add(deflection_from(cable, limit), 0.0, "cable", None)
            add(deflection_from(cable, -limit), 0.0, "cable", None)

        def flow_of(j: int) -> Callable[[float, FloatArray], float]:
            def torque(_t: float, y: FloatArray) -> float:
                psi, rate = unpack(y)
                acc, _ = model.accelerations(
                    psi, rate, engaged, held, direction, model.sliding_friction(rate)
                )
                return float(mode.flow[j] * model.mesh_torques(rate, acc, direction)[j])

            return torque

        for j in range(n):
            if mode.flow[j] != 0.0:
                add(flow_of(j), -1.0, "power_flow", j)
            g = model.group_of[j]
            if not model.meshed[j] and direction[g] > 0.0 and g in free:
                gap = self.wing.hinges[j].lost_motion / model.P[j, g]
                add(angle_of(free.index(g), gap), 1.0, "gear_engage", j)

        y0 = np.concatenate([psi0[free], rate0[free], self.thermal, np.zeros(4 * n)])
        end = min(stop_time, t0 + 1e4)
        sol = solve_ivp(
            rhs,
            (t0, end),
            y0,
            method="Radau",
            rtol=RTOL,
            atol=ATOL,
            events=events,
            dense_output=True,
        )
        if not sol.success:
            raise RuntimeError(sol.message)
        t1 = float(sol.t[-1])
        kind, group = "stop_time", None
        y1 = sol.y[:, -1]
        for i, times in enumerate(sol.t_events):
            if len(times):
                kind, group = meaning[i]
                y1 = sol.y_events[i][0]
                t1 = float(times[0])
                break
        dense = sol.sol

        def state(t: float, dense: Any = dense) -> tuple[FloatArray, FloatArray]:
            psi, rate = unpack(dense(t))
            return model.P @ psi, model.P @ rate

        out.segments.append(Segment(t0, t1, state))
        e = 2 * f + 2 * n
        energy["damper"] += y1[e : e + n]
        energy["friction"] += y1[e + n : e + 2 * n]
        energy["latch"] += y1[e + 2 * n : e + 3 * n]
        energy["gear"] += y1[e + 3 * n :]
        # The rotors' peak rises: at the steps (Radau at rtol 1e-11) and at the end.
        last = np.searchsorted(sol.t, t1, side="right")
        steps = np.concatenate([sol.y[2 * f : 2 * f + n, :last], y1[2 * f : 2 * f + n, None]], 1)
        self.peak_rise = np.maximum(self.peak_rise, np.max(steps, axis=1))
        self.thermal = y1[2 * f : e].copy()
        for j, h in enumerate(self.wing.hinges):
            if engaged[j] and h.latch_stiffness is not None:

                def torque(t: float, j: int = j, h: Hinge = h) -> float:
                    """Minus the compliant latch's |torque| (minimised: its peak)."""
                    assert h.latch_stiffness is not None
                    phi, dphi = state(t)
                    return -abs(
                        float(h.latch_stiffness * (phi[j] - h.travel) + h.latch_damping * dphi[j])
                    )

                grid = np.linspace(t0, t1, 401)
                values = [torque(float(s)) for s in grid]
                i = int(np.argmin(values))
                lo, hi = grid[max(i - 1, 0)], grid[min(i + 1, len(grid) - 1)]
                best = minimize_scalar(
                    torque,
                    bounds=(lo, hi),
                    method="bounded",
                    options={"xatol": 1e-12 * max(1.0, t1)},
                )
                peak[j] = max(peak[j], -float(best.fun), -values[i])
        psi, rate = unpack(y1)
        if kind == "cable":
            # "slack" where |delta| grows through a slack point, "taut" where it falls.
            phi, dphi = model.P @ psi, model.P @ rate
            kind = "taut"
            for c in model.elastic:
                assert c.stiffness is not None
                delta = phi[c.inboard + 1] - c.ratio * phi[c.inboard]
                ddelta = dphi[c.inboard + 1] - c.ratio * dphi[c.inboard]
                if abs(abs(delta) - c.slack_torque / c.stiffness) < 1e-9 and delta * ddelta > 0.0:
                    kind = "slack"
        return t1, psi, rate, kind, group


def ecd_at(
    temperature: float,
    *,
    bd: float,
    bd_coefficient: float,
    bg_fraction: float,
    fd: float,
    fl_slope: float,
    fl_at_0: float,
    fg: float,
    ratio: float,
    reference_temperature: float = 25.0,
) -> tuple[float, float]:
    """BECD_T and FECD_T of the paper's Eq. 1-4, typed here [N*m*s/rad], [N*m].

    ``BT = BD (1 + c (T - T_ref)) + BG`` (Eq. 1, BG = fraction x BD), ``FT = FD + FL_T + FG``
    (Eq. 2, FL_T linear), ``BECD = BT N^2``, ``FECD = FT N`` (Eq. 3-4).
    """
    bt = bd * (1.0 + bd_coefficient * (temperature - reference_temperature)) + bg_fraction * bd
    ft = fd + fl_slope * temperature + fl_at_0 + fg
    return bt * ratio * ratio, ft * ratio
