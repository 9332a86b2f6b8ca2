"""A wing as frozen dataclasses: panels, hinges with their springs, ECDs and latches, cables.

A wing is a planar chain of rigid panels from the root outwards (docs/wing.md): hinge 1
joins panel 1 to the spacecraft, hinge i joins panel i to panel i-1. Every hinge is a
single hinge of today's model in its own right: a spring over its travel, a hinge
friction over temperature, an ECD (Eq. 1-4) or none, a latch. So each hinge holds a
:class:`ecdsim.model.Load` (the spring, the travel, the friction law, a resistive
table) and an :class:`ecdsim.model.Ecd`, and :meth:`Hinge.at` evaluates them with the
same model functions the single-hinge method uses. The chain's inertia, its velocity
terms and a ground test's gravity come from :mod:`ecdsim.physics.chain`; a cable
loop's torque from :mod:`ecdsim.physics.cable`.

Angles: a hinge's *relative* angle q (the angle of its panel from the inboard panel, or
from the base's x axis for hinge 1; counter-clockwise positive) goes from
``stowed_angle`` to ``deployed_angle``. Its *deployed* angle phi, the coordinate of
today's single-hinge model, is 0 stowed and grows to the travel
``|deployed_angle - stowed_angle|`` at the latch: ``q = stowed + s phi`` with
``s = sign(deployed - stowed)``. Springs, frictions, ECDs and latches act on phi, as
they do on a single hinge.

Everything is SI, temperatures in degC. Fields are Python floats: a wing is one
configuration (a Monte Carlo over wing keys will vary the config and build wings).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from ecdsim._types import ArrayLike, FloatArray, as_float
from ecdsim.dynamics.params import DynamicParameters, Rolloff, Thermal
from ecdsim.model import (
    DeploymentSystem,
    Ecd,
    EcdState,
    Gearbox,
    Gravity,
    HighSpeedDamper,
    Load,
)
from ecdsim.physics import cable, chain, mechanics
from ecdsim.physics.gravity import STANDARD_GRAVITY


@dataclass(frozen=True)
class Panel:
    """One rigid panel of the chain.

    Attributes
    ----------
    name : the panel's name (tables, plots)
    mass : m [kg], > 0
    length : hinge-to-hinge length L, from its inboard hinge to its outboard hinge (the
        tip for the last panel) [m], > 0
    cg_along : a, the centre of gravity's distance along the panel from its inboard
        hinge [m]
    cg_across : b, the centre of gravity's offset across the panel (towards the panel's
        left, counter-clockwise from its axis) [m]
    inertia : the moment of inertia about the centre of gravity, about an axis normal to
        the plane (parallel to the hinge axes) [kg*m^2], >= 0
    thickness : the thickness drawn in pictures of the wing [m], >= 0; no dynamic effect
    """

    name: str
    mass: float
    length: float
    cg_along: float
    cg_across: float
    inertia: float
    thickness: float = 0.0

    def __post_init__(self) -> None:
        _require(self.mass > 0.0 and math.isfinite(self.mass), f"{self.name}: mass must be > 0")
        _require(
            self.length > 0.0 and math.isfinite(self.length), f"{self.name}: length must be > 0"
        )
        _require(self.inertia >= 0.0, f"{self.name}: inertia must be >= 0")
        _require(self.thickness >= 0.0, f"{self.name}: thickness must be >= 0")

    @property
    def hinge_inertia(self) -> float:
        """Moment of inertia about the inboard hinge, ``I + m (a^2 + b^2)`` [kg*m^2].

        The parallel-axis theorem (Meriam and Kraige, *Dynamics*, section B/1), the one
        panel's mass matrix of :func:`ecdsim.physics.chain.mass_matrix`.
        """
        matrix = chain.mass_matrix(
            np.zeros(1),
            np.array([self.mass]),
            np.array([self.cg_along]),
            np.array([self.cg_across]),
            np.array([self.inertia]),
            np.array([self.length]),
        )
        return float(matrix[0, 0])


@dataclass(frozen=True)
class HingeEcd:
    """The ECD at a hinge: every key of today's ``[damper]`` and ``[gearbox]``.

    The quasi-static part is an :class:`ecdsim.model.Ecd` (Eq. 1-4); the rest are the
    dynamic method's damper and gearbox parameters (docs/dynamics.md), with their
    meaning there.

    Attributes
    ----------
    ecd : the high-speed damper and the gearbox (Eq. 1-4; the gearbox's lost motion)
    source : where it was defined, e.g. ``"[wing.ecds.cc16]"`` or a catalogue entry
    rotor_inertia : the damper rotor's inertia at the high-speed shaft [kg*m^2]
    gearbox_inertia : the gear train's inertia at the high-speed shaft [kg*m^2]
    static_friction_factor : breakaway over kinetic FECD_T [-], >= 1
    stribeck_speed : Stribeck speed at the hinge (input) shaft [rad/s], or None
    rolloff : the damper's Kloss roll-off, or None for linear damping
    thermal : the damper's heat capacity (self-heating), or None
    gear_stiffness : the gear mesh's stiffness at the input shaft [N*m/rad], or None
        for a rigid mesh
    gear_mesh_damping : the mesh's damping at the input shaft [N*m*s/rad], or None
    """

    ecd: Ecd
    source: str = ""
    rotor_inertia: float = 0.0
    gearbox_inertia: float = 0.0
    static_friction_factor: float = 1.0
    stribeck_speed: float | None = None
    rolloff: Rolloff | None = None
    thermal: Thermal | None = None
    gear_stiffness: float | None = None
    gear_mesh_damping: float | None = None

    def at(self, temperature: ArrayLike) -> EcdState:
        """Eq. 1-4 at temperature(s) T [degC] (:meth:`ecdsim.model.Ecd.at`)."""
        return self.ecd.at(temperature)

    @property
    def reflected_inertia(self) -> float:
        """Rotor and gear train inertia seen at the hinge, ``(J_r + J_g) N^2`` [kg*m^2].

        :func:`ecdsim.physics.mechanics.reflect_inertia_to_input` (Wittenburg 2008, 3.3).
        """
        return float(
            mechanics.reflect_inertia_to_input(
                self.rotor_inertia + self.gearbox_inertia, self.ecd.gearbox.ratio
            )
        )

    @property
    def lost_motion(self) -> float:
        """The gearbox's lost motion at the hinge shaft [rad] (``[gearbox] lost_motion``)."""
        return self.ecd.gearbox.lost_motion


@dataclass(frozen=True)
class Latch:
    """What stops a hinge at its deployed angle.

    Rigid (``stiffness`` None): an end stop with the coefficient of restitution
    ``restitution``, 0 a latch that catches at once (today's ``[load] restitution``).
    Compliant: from its first arrival at the deployed angle the latch holds the hinge
    both ways with a torque ``-stiffness (phi - travel) - damping phi'`` (the latch's
    shock is resolved and its peak torque reported).

    Attributes
    ----------
    restitution : e of a rigid latch [-], in [0, 1)
    stiffness : the latch's torsional stiffness at the hinge [N*m/rad], > 0, or None
    damping : the latch's damping at the hinge [N*m*s/rad], >= 0 (compliant only)
    """

    restitution: float = 0.0
    stiffness: float | None = None
    damping: float = 0.0

    def __post_init__(self) -> None:
        _require(0.0 <= self.restitution < 1.0, "latch restitution must be in [0, 1)")
        _require(self.stiffness is None or self.stiffness > 0.0, "latch stiffness must be > 0")
        _require(self.damping >= 0.0, "latch damping must be >= 0")
        _require(
            self.stiffness is not None or self.damping == 0.0,
            "latch damping needs a latch stiffness",
        )
        _require(
            self.stiffness is None or self.restitution == 0.0,
            "a compliant latch has no restitution (its damping sets the losses)",
        )

    @property
    def rigid(self) -> bool:
        """True for a rigid end stop (restitution), False for a compliant latch."""
        return self.stiffness is None

    def torque(self, overshoot: float, speed: float) -> float:
        """A compliant latch's torque at ``phi - travel`` [rad] and ``phi'`` [rad/s] [N*m].

        A linear spring and damper in parallel (Kelvin-Voigt), holding the hinge both ways.
        """
        assert self.stiffness is not None
        return -self.stiffness * overshoot - self.damping * speed


@dataclass(frozen=True)
class HingeState:
    """One hinge at temperature(s) T: what its equations need, referred to the hinge.

    Attributes
    ----------
    temperature : T [degC]
    ecd : the ECD's state (Eq. 1-4), None for an undamped hinge
    damping_rate : BECD_T (Eq. 3), 0 without an ECD [N*m*s/rad]
    ecd_friction : FECD_T (Eq. 4), 0 without an ECD [N*m]
    hinge_friction : the hinge friction at T (the single hinge's FS_T) [N*m]
    kinetic_friction : FECD_T + FS_T [N*m]
    breakaway_friction : ``f_D FECD_T + f_S FS_T`` [N*m] (docs/dynamics.md, stiction)
    """

    temperature: FloatArray
    ecd: EcdState | None
    damping_rate: FloatArray
    ecd_friction: FloatArray
    hinge_friction: FloatArray
    kinetic_friction: FloatArray
    breakaway_friction: FloatArray


@dataclass(frozen=True)
class Hinge:
    """One hinge: its angles, spring, friction, ECD and latch.

    Attributes
    ----------
    name : the hinge's name (tables, plots)
    stowed_angle : relative angle q at release [rad]
    deployed_angle : relative angle q at the latch [rad], != stowed_angle
    load : the spring over the hinge's travel (deployed angle 0 stowed, the travel at
        the latch), the hinge friction law (FS_T) and a resistive table; its travel is
        ``|deployed_angle - stowed_angle|`` and it has no gravity (the wing's ground
        test acts on the panels)
    ecd : the hinge's ECD, None for an undamped hinge
    latch : the latch at the deployed angle
    static_friction_factor : breakaway over kinetic hinge friction [-], >= 1; None =
        the ECD's factor (1 without an ECD), as ``[load] static_friction_factor``
    """

    name: str
    stowed_angle: float
    deployed_angle: float
    load: Load
    ecd: HingeEcd | None = None
    latch: Latch = field(default_factory=Latch)
    static_friction_factor: float | None = None

    def __post_init__(self) -> None:
        _require(
            self.deployed_angle != self.stowed_angle,
            f"{self.name}: deployed_angle must differ from stowed_angle",
        )
        _require(
            math.isclose(float(np.max(self.load.travel)), self.travel, rel_tol=1e-12),
            f"{self.name}: the load's travel must be |deployed_angle - stowed_angle|",
        )
        _require(self.load.gravity is None, f"{self.name}: gravity belongs to the wing")

    @property
    def travel(self) -> float:
        """The hinge's travel, ``|deployed_angle - stowed_angle|`` [rad]."""
        return abs(self.deployed_angle - self.stowed_angle)

    @property
    def direction(self) -> float:
        """s = +1 where the relative angle grows as the hinge deploys, else -1."""
        return 1.0 if self.deployed_angle > self.stowed_angle else -1.0

    @property
    def system_static_friction_factor(self) -> float:
        """The hinge friction's breakaway factor, defaulting to the ECD's."""
        if self.static_friction_factor is not None:
            return self.static_friction_factor
        return 1.0 if self.ecd is None else self.ecd.static_friction_factor

    def relative_angle(self, deployed: ArrayLike) -> FloatArray:
        """The relative angle q of deployed angle(s) phi: ``stowed + s phi`` [rad]."""
        return as_float(self.stowed_angle + self.direction * as_float(deployed))

    def deployed(self, relative: ArrayLike) -> FloatArray:
        """The deployed angle phi of relative angle(s) q: ``s (q - stowed)`` [rad]."""
        return as_float(self.direction * (as_float(relative) - self.stowed_angle))

    def drive_torque(self, deployed: ArrayLike, temperature: ArrayLike) -> FloatArray:
        """Spring less resistive table at deployed angle(s) phi [N*m], deploying positive.

        The single hinge's net drive, ``Load.drive.torque_at``; within the travel.
        """
        return self.load.drive.torque_at(deployed, self.travel, temperature)

    def at(self, temperature: ArrayLike) -> HingeState:
        """The hinge's ECD (Eq. 1-4) and friction values at temperature(s) T [degC].

        The same model calls as the single hinge (:meth:`ecdsim.model.Ecd.at`, the
        friction law); the breakaway is the dynamic method's ``f_D FECD_T + f_S FS_T``.
        """
        t = as_float(temperature)
        hinge_friction = as_float(self.load.system_friction(t))
        zero = np.zeros_like(t)
        if self.ecd is None:
            state = None
            damping, ecd_friction, factor = zero, zero, 1.0
        else:
            state = self.ecd.at(t)
            damping = as_float(np.broadcast_to(state.ecd_damping_rate, t.shape))
            ecd_friction = as_float(np.broadcast_to(state.ecd_friction, t.shape))
            factor = self.ecd.static_friction_factor
        return HingeState(
            temperature=t,
            ecd=state,
            damping_rate=damping,
            ecd_friction=ecd_friction,
            hinge_friction=hinge_friction,
            kinetic_friction=as_float(ecd_friction + hinge_friction),
            breakaway_friction=as_float(
                factor * ecd_friction + self.system_static_friction_factor * hinge_friction
            ),
        )


@dataclass(frozen=True)
class Cable:
    """A closed cable loop between hinge ``inboard`` and the next one outwards.

    It holds ``phi_outboard = ratio * phi_inboard`` (deployed angles): rigidly (a
    holonomic constraint) without ``stiffness``, else elastically with the law of
    :mod:`ecdsim.physics.cable` (its stiffness halving where a strand slackens).

    Attributes
    ----------
    inboard : index of the inboard hinge (0 for the root hinge); the cable couples it
        with hinge ``inboard + 1``
    ratio : r, deployed angle of the outboard hinge per deployed angle of the inboard [-]
    stiffness : K, the loop's torsional stiffness with both strands taut, at the
        outboard hinge [N*m/rad], or None for a rigid cable
    slack_torque : tau_s = 2 T0 rho, the torque at which a strand slackens (pretension
        T0, outboard pulley radius rho) [N*m]; None with a rigid cable
    """

    inboard: int
    ratio: float
    stiffness: float | None = None
    slack_torque: float | None = None

    def __post_init__(self) -> None:
        _require(self.inboard >= 0, "cable inboard hinge index must be >= 0")
        _require(self.ratio > 0.0 and math.isfinite(self.ratio), "cable ratio must be > 0")
        _require(
            (self.stiffness is None) == (self.slack_torque is None),
            "an elastic cable needs both stiffness and slack_torque; a rigid one neither",
        )
        _require(self.stiffness is None or self.stiffness > 0.0, "cable stiffness must be > 0")
        _require(
            self.slack_torque is None or self.slack_torque >= 0.0,
            "cable slack torque must be >= 0",
        )

    @property
    def outboard(self) -> int:
        """Index of the outboard hinge."""
        return self.inboard + 1

    @property
    def rigid(self) -> bool:
        """True for a rigid cable (a constraint), False for an elastic one."""
        return self.stiffness is None

    def deflection(self, deployed: FloatArray) -> float:
        """delta = phi_outboard - r phi_inboard of the wing's deployed angles [rad]."""
        return float(deployed[self.outboard] - self.ratio * deployed[self.inboard])

    def torque(self, deployed: FloatArray) -> float:
        """The elastic loop's torque on the outboard hinge [N*m] (:func:`cable_torque`)."""
        assert self.stiffness is not None
        assert self.slack_torque is not None
        return cable.cable_torque(self.deflection(deployed), self.stiffness, self.slack_torque)

    def energy(self, deployed: FloatArray) -> float:
        """The elastic loop's stored energy [J] (:func:`cable_energy`)."""
        assert self.stiffness is not None
        assert self.slack_torque is not None
        return cable.cable_energy(self.deflection(deployed), self.stiffness, self.slack_torque)


@dataclass(frozen=True)
class GroundTest:
    """Gravity on the panels in a ground test, with a per-panel offload.

    Attributes
    ----------
    direction : the direction gravity points, in the wing's plane, from the base's x
        axis, counter-clockwise [rad] (-pi/2: along -y)
    offload : the fraction of each panel's weight carried by the ground-support
        equipment at its centre of gravity [-], one per panel, each in [0, 1]
    acceleration : g [m/s^2], standard gravity
    """

    direction: float
    offload: tuple[float, ...]
    acceleration: float = STANDARD_GRAVITY

    def __post_init__(self) -> None:
        _require(all(0.0 <= o <= 1.0 for o in self.offload), "offload must be in [0, 1]")

    @property
    def gravity(self) -> tuple[float, float]:
        """The gravity vector's components along the base's x and y axes [m/s^2]."""
        return (
            self.acceleration * math.cos(self.direction),
            self.acceleration * math.sin(self.direction),
        )


@dataclass(frozen=True)
class WingState:
    """Every hinge of a wing at temperature(s) T.

    Attributes
    ----------
    temperature : T [degC]
    hinges : one :class:`HingeState` per hinge, root first
    """

    temperature: FloatArray
    hinges: tuple[HingeState, ...]


@dataclass(frozen=True)
class Wing:
    """A planar chain of panels from the root outwards, a hinge inboard of each.

    Attributes
    ----------
    name : the wing's name (the config's title)
    panels : the panels, root first
    hinges : the hinges, root first; hinge i is at panel i's inboard end
    cables : closed cable loops between adjacent hinges
    ground_test : gravity in a ground test, None for flight (0 g)
    """

    name: str
    panels: tuple[Panel, ...]
    hinges: tuple[Hinge, ...]
    cables: tuple[Cable, ...] = ()
    ground_test: GroundTest | None = None

    def __post_init__(self) -> None:
        _require(len(self.panels) >= 1, "a wing needs at least one panel")
        _require(len(self.hinges) == len(self.panels), "a wing has one hinge inboard of each panel")
        pairs = [c.inboard for c in self.cables]
        _require(len(set(pairs)) == len(pairs), "at most one cable between two hinges")
        _require(
            all(c.outboard < len(self.hinges) for c in self.cables),
            "a cable couples two hinges of the wing",
        )
        if self.ground_test is not None:
            _require(
                len(self.ground_test.offload) == len(self.panels),
                "the ground test needs one offload per panel",
            )

    @property
    def size(self) -> int:
        """The number of panels (and of hinges)."""
        return len(self.panels)

    def chain_arrays(self) -> dict[str, FloatArray]:
        """The panels as the arrays of :mod:`ecdsim.physics.chain` (SI).

        Keys ``mass``, ``cg_along``, ``cg_across``, ``inertia``, ``length``,
        ``thickness`` and ``offload`` (zeros in flight).
        """
        offload = self.ground_test.offload if self.ground_test is not None else (0.0,) * self.size
        return {
            "mass": np.array([p.mass for p in self.panels]),
            "cg_along": np.array([p.cg_along for p in self.panels]),
            "cg_across": np.array([p.cg_across for p in self.panels]),
            "inertia": np.array([p.inertia for p in self.panels]),
            "length": np.array([p.length for p in self.panels]),
            "thickness": np.array([p.thickness for p in self.panels]),
            "offload": np.array(offload, dtype=float),
        }

    @property
    def stowed_angles(self) -> FloatArray:
        """Relative hinge angles at release [rad]."""
        return np.array([h.stowed_angle for h in self.hinges])

    @property
    def deployed_angles(self) -> FloatArray:
        """Relative hinge angles at the latches [rad]."""
        return np.array([h.deployed_angle for h in self.hinges])

    @property
    def travels(self) -> FloatArray:
        """Each hinge's travel [rad]."""
        return np.array([h.travel for h in self.hinges])

    @property
    def directions(self) -> FloatArray:
        """Each hinge's s, +1 where its relative angle grows as it deploys, else -1."""
        return np.array([h.direction for h in self.hinges])

    def relative_angles(self, deployed: ArrayLike) -> FloatArray:
        """Relative angles q of the hinges' deployed angles phi (last axis: hinges)."""
        return as_float(self.stowed_angles + self.directions * as_float(deployed))

    def outlines(self, deployed: ArrayLike) -> FloatArray:
        """The panels' outlines at deployed angles phi, (n, 4, 2) [m].

        :func:`ecdsim.physics.chain.panel_outlines` with each panel's drawn thickness.
        """
        arrays = self.chain_arrays()
        return chain.panel_outlines(
            self.relative_angles(deployed), arrays["length"], arrays["thickness"]
        )

    def at(self, temperature: ArrayLike) -> WingState:
        """Every hinge's ECD and friction values at temperature(s) T [degC]."""
        t = as_float(temperature)
        return WingState(t, tuple(h.at(t) for h in self.hinges))

    def as_single_hinge(self) -> tuple[DeploymentSystem, DynamicParameters]:
        """A one-panel wing as today's single hinge: its system and dynamic parameters.

        The panel's inertia about the hinge is the load inertia; the hinge's spring,
        friction and ECD are the system's; a ground test becomes ``[load.gravity]`` with
        the centre of gravity's radius and its release angle from gravity, measured in
        the direction of deployment (docs/wing.md). Refused (ValueError) for more than
        one panel or a compliant latch (the single hinge has a rigid end stop only).
        """
        _require(self.size == 1, "only a one-panel wing is a single hinge")
        panel, hinge = self.panels[0], self.hinges[0]
        _require(hinge.latch.rigid, "a compliant latch has no single-hinge equivalent")
        load = hinge.load
        if self.ground_test is not None:
            radius = math.hypot(panel.cg_along, panel.cg_across)
            # The angle from gravity to the hinge-to-CG line at release, in the direction
            # of deployment: s (q_stowed + atan2(b, a) - gravity direction), wrapped.
            beta = math.atan2(panel.cg_across, panel.cg_along)
            angle = hinge.direction * (hinge.stowed_angle + beta - self.ground_test.direction)
            release = math.remainder(angle, 2.0 * math.pi)
            gravity = Gravity(panel.mass, radius, release, self.ground_test.offload[0])
            load = Load(
                spring=load.spring,
                travel=load.travel,
                system_friction=load.system_friction,
                resistance=load.resistance,
                gravity=gravity,
            )
        ecd = hinge.ecd if hinge.ecd is not None else _NO_ECD
        system = DeploymentSystem(ecd.ecd, load, name=self.name)
        dynamics = DynamicParameters(
            load_inertia=panel.hinge_inertia,
            rotor_inertia=ecd.rotor_inertia,
            gearbox_inertia=ecd.gearbox_inertia,
            static_friction_factor=ecd.static_friction_factor,
            system_static_friction_factor=hinge.system_static_friction_factor,
            stribeck_speed=ecd.stribeck_speed,
            restitution=hinge.latch.restitution,
            rolloff=ecd.rolloff,
            thermal=ecd.thermal,
            gear_stiffness=ecd.gear_stiffness,
            gear_mesh_damping=ecd.gear_mesh_damping,
        )
        return system, dynamics


# An undamped hinge as a single hinge: no damping, no friction, no inertia (ratio 1).
_NO_ECD = HingeEcd(
    Ecd(
        HighSpeedDamper(damping_rate=0.0, damping_temperature_coefficient=0.0),
        Gearbox(ratio=1.0, coulomb_friction=0.0, damping_rate=0.0),
    ),
    source="none",
)


def _require(condition: bool, message: str) -> None:
    if not condition:
        raise ValueError(message)
