"""The engaged equations of the nonlinear segments, vectorised over a set of segments.

In the forward frame of a segment (``x`` the displacement and ``u`` the speed in the
direction of motion, friction folded into the drive ``a`` as in
:mod:`ecdsim.dynamics.linear`), the state ``y = [x, u, s, E]`` obeys

    x' = u
    J u' = a - k x - N (T_eddy(N u, f) + BG N u)
    s' = (p(N u, f) - (T_d - T_ambient) / (R f)) / C      (if heating is modelled, else 0)
    E' = N (T_eddy(N u, f) + BG N u) u                      (damper dissipation)

with ``f = f_a exp(c s)`` the damping law's temperature factor (``1 + c (T_d - T_ref)``:
Eq. 1's bracket, or the Kloss peak speed's resistivity factor), ``f_a`` its value at the
ambient temperature and ``p = T_eddy N u / f`` the eddy-current power over it. ``s`` is
the factor's logarithm over c, in kelvin (``T_d - T_ambient`` over ``f_a`` to first
order, exactly at c = 0); the damper temperature is ``T_d = T_ambient + f_a s E(c s)``
(:mod:`ecdsim.physics.thermal`, where the heat balance is rewritten for s).

Why s and not T_d: where c < 0 the factor, the damping and the heating power all vanish
at ``T_zero = T_ref - 1/c``, which the true temperature approaches but never reaches (the
power ``f p`` vanishes with f, so f decays at most exponentially). An integrator of T_d
overshoots it by its error and then evaluates the law where it has no meaning
(``BD_T < 0``); with s every state, even a rejected trial step's, has ``f > 0``, and the
approach to T_zero is the smooth growth of s. The invariant holds by construction, so
the answer does not depend on the tolerance. (Only the eddy-current power heats the
damper's conductor; gearbox damping and friction losses heat other parts.)

Stribeck friction (optional): with a Stribeck speed ``w_St`` the sliding friction is

    F(u) = F_C + (F_brk - F_C) exp(-(u / w_St)^2)        (u >= 0, forward frame)

(the Gaussian Stribeck curve of the LuGre model, Canudas de Wit et al., IEEE TAC 40(3),
1995; no viscous term here: the damper's is the eddy law and BG).
The Coulomb part ``F_C`` stays folded into the drive ``a``; the excess ``F_brk - F_C``
decays with speed, so ``J u' = a - k x - M_d - g(u)`` and ``E' = (M_d + g(u)) u`` with
``g = (F_brk - F_C) exp(-(u / w_St)^2)`` (:func:`stribeck_excess`): E then counts the
Stribeck excess's dissipation with the damper's.

Two-node heating (optional): with a housing heat capacity ``C_h`` the state has a fifth
row, the housing's rise over the ambient (environment) temperature ``h = T_h - T_ambient``
[K], and R is the rotor-to-housing resistance:

    s' = (p - (T_d - T_ambient) / (R f) + h / (R f)) / C
    h' = ((T_d - T_ambient - h) / R - h / R_he) / C_h

(:mod:`ecdsim.physics.thermal`, two nodes). The rotor keeps the log state, so the
invariant above holds for it unchanged; the housing is never hotter than the rotor's
bound in exact arithmetic (it is heated only by the rotor).

Lossy gear (optional, docs/model.md): with a mesh factor ``m`` (1/eta_f while the load
drives the damper side, eta_b while it is back-driven; constant over a segment) the
damper side's torque reaches the input times m, ``J u' = a - k x - m M_d`` (J already
holds ``J_L + m J_D``), while E and the heating keep the damper's own ``M_d`` (the mesh
loss is booked apart). The segment ends where the power flow reverses: where the
indicator ``J_L (M_d + F_q) + J_D (a_L - k x - G(x))`` (:meth:`Model.indicator`,
:func:`ecdsim.physics.gearing.power_flow_indicator`) changes sign.

Both integrators of :mod:`ecdsim.dynamics.integrate` use this one :class:`Model`.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from ecdsim._types import FloatArray, broadcast
from ecdsim.dynamics.damping import EddyLaw
from ecdsim.physics import thermal
from ecdsim.physics.gravity import gravity_torque, gravity_torque_slope

# Event code of a segment that ends where a lossy gear's power flow reverses (after
# linear's REACH, ZERO, CAP, REST and integrate's HORIZON).
SWITCH = 5


def stribeck_excess(
    speed: FloatArray, excess: FloatArray, stribeck_speed: FloatArray
) -> tuple[FloatArray, FloatArray]:
    """The Stribeck part of the sliding friction above Coulomb, and its slope in speed.

    ``g(u) = (F_brk - F_C) exp(-(u / w_St)^2)``: the steady-state Stribeck curve
    ``g(v) = F_C + (F_s - F_C) exp(-(v / v_s)^2)`` of the LuGre model (Canudas de Wit,
    Olsson, Astrom and Lischinsky, "A new model for control of systems with friction",
    IEEE Trans. Automatic Control 40(3), 419-425, 1995), one of the forms reviewed by
    Armstrong-Helouvry, Dupont and Canudas de Wit, Automatica 30(7), 1994. The breakaway
    is at rest (u = 0) and w_St is used as given (Simscape's Rotational Friction instead
    peaks near T_brk at a breakaway speed w_brk, with w_St = sqrt(2) w_brk and a sqrt(2 e)
    scale; docs/model.md).

    Parameters
    ----------
    speed : u, sliding speed at the input shaft [rad/s]
    excess : F_brk - F_C, breakaway over Coulomb friction [N*m], >= 0
    stribeck_speed : w_St [rad/s], > 0

    Returns
    -------
    g : the friction above Coulomb at u [N*m]
    slope : dg/du [N*m*s/rad]

    >>> g, slope = stribeck_excess(np.array([0.0, 2.0]), np.array([1.0, 1.0]), 2.0)
    >>> [round(float(v), 12) for v in g], [round(float(v), 12) for v in slope]
    ([1.0, 0.367879441171], [-0.0, -0.367879441171])
    """
    ratio = speed / stribeck_speed
    g = excess * np.exp(-ratio * ratio)
    return g, -2.0 * ratio / stribeck_speed * g


@dataclass(frozen=True)
class Model:
    """The engaged equations of a set of segments, in the forward frame (1-D arrays).

    Attributes
    ----------
    inertia : J [kg*m^2]
    stiffness : k, fall of the spring torque per radian [N*m/rad]
    drive : a, spring torque minus friction at the segment's start [N*m]
    ratio : gear ratio N [-]
    gearbox_damping : BG at the high-speed shaft [N*m*s/rad]
    heat_capacity : C [J/K]
    thermal_resistance : R [K/W] (inf: adiabatic)
    ambient : ambient temperature, where s = 0 [degC]
    eddy : the eddy-current law, one case per segment
    heating : whether the damper temperature evolves
    ambient_factor : f_a, the law's temperature factor at ambient [-]; computed when None
    stribeck_excess : F_brk - F_C [N*m] of each segment, or None for no Stribeck friction
    stribeck_speed : w_St [rad/s] of each segment (with ``stribeck_excess``)
    housing_heat_capacity : C_h [J/K] of each segment, or None for one-node heating
    housing_resistance : R_he, housing to ambient [K/W] (with ``housing_heat_capacity``)
    gravity_amplitude : W = m g r (1 - offload) of a ground test [N*m] per segment, or
        None for no gravity (docs/model.md, gravity in ground tests)
    gravity_phase : theta_0 + phi at the segment's start [rad] (with ``gravity_amplitude``)
    gravity_direction : +1 forward, -1 backward: the segment's frame (with the amplitude)
    mesh : m, a lossy gear's factor on the damper side's torque [-] per segment, or None
        for an ideal gear (then the next five are None too)
    flow : +1 forward, -1 back-driven: the power flow whose reversal ends the segment
        (0: no such event, e.g. in free play)
    load_inertia : J_L [kg*m^2]
    damper_inertia : J_D, the damper side at the input [kg*m^2]
    mesh_friction : F_q = FT_T N, the damper side's Coulomb friction through an ideal
        gear [N*m]
    load_drive : a_L, spring torque less the system friction at the start [N*m]
    """

    inertia: FloatArray
    stiffness: FloatArray
    drive: FloatArray
    ratio: FloatArray
    gearbox_damping: FloatArray
    heat_capacity: FloatArray
    thermal_resistance: FloatArray
    ambient: FloatArray
    eddy: EddyLaw
    heating: bool
    ambient_factor: FloatArray | None = None
    stribeck_excess: FloatArray | None = None
    stribeck_speed: FloatArray | None = None
    housing_heat_capacity: FloatArray | None = None
    housing_resistance: FloatArray | None = None
    gravity_amplitude: FloatArray | None = None
    gravity_phase: FloatArray | None = None
    gravity_direction: FloatArray | None = None
    mesh: FloatArray | None = None
    flow: FloatArray | None = None
    load_inertia: FloatArray | None = None
    damper_inertia: FloatArray | None = None
    mesh_friction: FloatArray | None = None
    load_drive: FloatArray | None = None

    @property
    def two_node(self) -> bool:
        """True when the state has the housing row (index 4)."""
        return self.heating and self.housing_heat_capacity is not None

    @property
    def rows(self) -> int:
        """The state's length: 5 with a housing node, else 4."""
        return 5 if self.two_node else 4

    def __post_init__(self) -> None:
        if self.ambient_factor is None:
            # The problem's domain checks keep f_a >= 0 (Eq. 1's BD_T >= 0 at ambient, a
            # positive peak speed); the clip only removes rounding at the law's zero.
            factor = np.maximum(self.eddy.factor(self.ambient), 0.0)
            object.__setattr__(self, "ambient_factor", broadcast(factor, np.shape(self.inertia)))

    @property
    def _factor_at_ambient(self) -> FloatArray:
        factor = self.ambient_factor
        assert factor is not None  # set in __post_init__
        return factor

    def take(self, index: NDArray[np.intp]) -> Model:
        """The model of a subset of the segments."""
        return Model(
            inertia=self.inertia[index],
            stiffness=self.stiffness[index],
            drive=self.drive[index],
            ratio=self.ratio[index],
            gearbox_damping=self.gearbox_damping[index],
            heat_capacity=self.heat_capacity[index],
            thermal_resistance=self.thermal_resistance[index],
            ambient=self.ambient[index],
            eddy=self.eddy.take(index),
            heating=self.heating,
            ambient_factor=self._factor_at_ambient[index],
            stribeck_excess=None if self.stribeck_excess is None else self.stribeck_excess[index],
            stribeck_speed=None if self.stribeck_speed is None else self.stribeck_speed[index],
            housing_heat_capacity=None
            if self.housing_heat_capacity is None
            else self.housing_heat_capacity[index],
            housing_resistance=None
            if self.housing_resistance is None
            else self.housing_resistance[index],
            gravity_amplitude=None
            if self.gravity_amplitude is None
            else self.gravity_amplitude[index],
            gravity_phase=None if self.gravity_phase is None else self.gravity_phase[index],
            gravity_direction=None
            if self.gravity_direction is None
            else self.gravity_direction[index],
            **self._mesh_take(index),
        )

    def _mesh_take(self, index: NDArray[np.intp]) -> dict[str, FloatArray]:
        """The lossy gear's fields of a subset of the segments (none for an ideal gear)."""
        names = ("mesh", "flow", "load_inertia", "damper_inertia", "mesh_friction", "load_drive")
        taken: dict[str, FloatArray] = {}
        for name in names:
            value = getattr(self, name)
            if value is not None:
                taken[name] = value[index]
        return taken

    def indicator(self, y: FloatArray) -> FloatArray:
        """``flow * (J_L (M_d + F_q) + J_D (a_L - k x - G(x)))`` at states y (rows, n).

        Positive while the power flows as the segment assumes; the segment ends where it
        falls to zero (docs/model.md, lossy gear). Zero everywhere without a mesh.
        """
        if self.mesh is None:
            return np.zeros_like(y[1])
        assert self.flow is not None
        assert self.load_inertia is not None
        assert self.damper_inertia is not None
        assert self.mesh_friction is not None
        assert self.load_drive is not None
        x, u = y[0], y[1]
        shaft = self.ratio * u
        eddy = self.eddy.torque_at_factor(shaft, self.factor(y[2]))
        damper = self.ratio * (eddy + self.gearbox_damping * shaft) + self.mesh_friction
        load = self.load_drive - self.stiffness * x
        weight = self.gravity(x)
        if weight is not None:
            load = load - weight[0]
        return np.asarray(self.flow * (self.load_inertia * damper + self.damper_inertia * load))

    def gravity(self, x: FloatArray) -> tuple[FloatArray, FloatArray] | None:
        """The gravity torque against the motion in the forward frame, and its slope in x.

        ``G(x) = d W sin(theta_0 + phi_0 + d x)`` with d the direction (the torque
        opposing deployment, :func:`ecdsim.physics.gravity.gravity_torque`, seen along the
        motion), ``dG/dx = W cos(theta_0 + phi_0 + d x)``; None without gravity.
        """
        if self.gravity_amplitude is None:
            return None
        assert self.gravity_phase is not None
        assert self.gravity_direction is not None
        angle = self.gravity_phase + self.gravity_direction * x
        torque = self.gravity_direction * gravity_torque(0.0, self.gravity_amplitude, angle)
        return torque, gravity_torque_slope(0.0, self.gravity_amplitude, angle)

    def rest_push(self, x: FloatArray) -> FloatArray:
        """``J u'`` at ``u = 0+`` and displacement x: ``a - k x - g(0) - G(x)`` [N*m].

        The damping torque vanishes at rest (both laws and BG are zero at zero speed), the
        Stribeck excess is its breakaway value ``g(0) = F_brk - F_C``. Positive while the
        load is short of its static equilibrium: a speed that falls towards zero there
        is an asymptotic approach to rest (creep); zero or negative once the load is past
        it, where the speed reaches zero in finite time (docs/dynamics.md, the events).
        """
        push = self.drive - self.stiffness * x
        if self.stribeck_excess is not None:
            push = push - self.stribeck_excess
        weight = self.gravity(x)
        if weight is not None:
            push = push - weight[0]
        return np.asarray(push)

    def _stribeck(self, u: FloatArray) -> tuple[FloatArray, FloatArray] | None:
        if self.stribeck_excess is None or self.stribeck_speed is None:
            return None
        return stribeck_excess(u, self.stribeck_excess, self.stribeck_speed)

    def factor(self, state: FloatArray) -> FloatArray:
        """The damping law's temperature factor ``f = f_a exp(c s)`` [-]."""
        return thermal.damping_factor_from_log(
            state, self._factor_at_ambient, self.eddy.coefficient
        )

    def temperature(self, state: FloatArray) -> FloatArray:
        """The damper temperature at states s (broadcast over leading axes) [degC].

        Where c < 0 the true temperature stays below the law's zero ``T_ref - 1/c``; the
        reconstruction's rounding (a few ulp once f is below 1e-16) is clipped to it.
        """
        c = self.eddy.coefficient
        temperature = thermal.temperature_from_factor_log(
            state, self.ambient, self._factor_at_ambient, c
        )
        falling = c < 0.0
        zero = np.asarray(self.eddy.reference_temperature, float) - 1.0 / np.where(falling, c, -1.0)
        return np.minimum(temperature, np.where(falling, zero, np.inf))

    def rhs(self, y: FloatArray, out: FloatArray | None = None) -> FloatArray:
        """``dy/dt``, shape (rows, n), written into ``out`` if given (which must not be y)."""
        x, u, s = y[0], y[1], y[2]
        dy = np.empty_like(y) if out is None else out
        factor = self.factor(s)
        shaft = self.ratio * u
        eddy = self.eddy.torque_at_factor(shaft, factor)
        torque = self.ratio * (eddy + self.gearbox_damping * shaft)
        accel = dy[1]
        np.multiply(self.stiffness, x, out=accel)
        np.subtract(self.drive, accel, out=accel)
        accel -= torque if self.mesh is None else self.mesh * torque
        stribeck = self._stribeck(u)
        if stribeck is not None:
            accel -= stribeck[0]
        weight = self.gravity(x)
        if weight is not None:
            accel -= weight[0]
        accel /= self.inertia
        if self.heating:
            dy[2] = thermal.factor_log_rate(
                self.eddy.power_per_factor(shaft, factor),
                s,
                self.heat_capacity,
                self.thermal_resistance,
                self.eddy.coefficient,
            )
            if self.two_node:
                self._housing_rhs(y, factor, dy)
        else:
            dy[2] = 0.0
        if stribeck is not None:
            np.multiply(torque + stribeck[0], u, out=dy[3])
        else:
            np.multiply(torque, u, out=dy[3])
        dy[0] = u
        return dy

    def jacobian(self, y: FloatArray) -> tuple[FloatArray, ...]:
        """Nonzero entries (j10, j11, j12, j21, j22, j31, j32) of ``df/dy``."""
        u, s = y[1], y[2]
        n = self.ratio
        c = self.eddy.coefficient
        factor = self.factor(s)
        shaft = n * u
        eddy = self.eddy.torque_at_factor(shaft, factor)
        d_speed = self.eddy.speed_derivative_at_factor(shaft, factor)
        d_factor = self.eddy.factor_derivative(shaft, factor)
        torque = n * (eddy + self.gearbox_damping * shaft)
        d_torque_du = n * n * (d_speed + self.gearbox_damping)
        d_torque_ds = n * d_factor * (c * factor)  # df/ds = c f
        j10 = -self.stiffness / self.inertia
        weight = self.gravity(y[0])
        if weight is not None:
            j10 = -(self.stiffness + weight[1]) / self.inertia
        if self.mesh is None:
            j11 = -d_torque_du / self.inertia
            j12 = -d_torque_ds / self.inertia
        else:
            # The lossy gear's m on M_d in the motion, not in E (the damper's own work);
            # Stribeck friction is not taken with a mesh.
            j11 = -self.mesh * d_torque_du / self.inertia
            j12 = -self.mesh * d_torque_ds / self.inertia
        if self.heating:
            by_speed, by_factor = self.eddy.power_per_factor_derivatives(shaft, factor)
            j21 = n * by_speed / self.heat_capacity
            j22 = thermal.factor_log_rate_slope(
                by_factor, factor, s, self.heat_capacity, self.thermal_resistance, c
            )
        else:
            j21 = np.zeros_like(u)
            j22 = np.zeros_like(u)
        stribeck = self._stribeck(u)
        if stribeck is not None:
            torque = torque + stribeck[0]
            d_torque_du = d_torque_du + stribeck[1]
            j11 = -d_torque_du / self.inertia
        j31 = torque + d_torque_du * u
        j32 = d_torque_ds * u
        if self.two_node:
            # d/ds of the housing's return h / (R f C) (df/ds = c f)
            j22 = j22 - c * thermal.housing_return(
                y[4], factor, self.thermal_resistance, self.heat_capacity
            )
        return j10, j11, j12, j21, j22, j31, j32

    def _housing_rhs(self, y: FloatArray, factor: FloatArray, dy: FloatArray) -> None:
        """The two-node terms: the housing's return into ``dy[2]`` and ``dy[4]``."""
        assert self.housing_heat_capacity is not None
        assert self.housing_resistance is not None
        housing = y[4]
        dy[2] += thermal.housing_return(
            housing, factor, self.thermal_resistance, self.heat_capacity
        )
        rise = thermal.temperature_from_factor_log(
            y[2], 0.0, self._factor_at_ambient, self.eddy.coefficient
        )
        dy[4] = thermal.housing_rate(
            rise,
            housing,
            self.housing_heat_capacity,
            self.thermal_resistance,
            self.housing_resistance,
        )

    def housing_jacobian(self, y: FloatArray) -> tuple[FloatArray, FloatArray, FloatArray]:
        """The two-node entries (j24, j42, j44) of ``df/dy`` (zeros without a housing).

        ``j24 = 1 / (R f C)`` (the housing's return), ``j42 = f / (R C_h)`` (dT_d/ds = f),
        ``j44 = -(1 / R + 1 / R_he) / C_h``.
        """
        if not self.two_node:
            zero = np.zeros_like(y[1])
            return zero, zero, zero
        assert self.housing_heat_capacity is not None
        assert self.housing_resistance is not None
        factor = self.factor(y[2])
        ones = np.ones_like(y[1])
        j24 = thermal.housing_return(ones, factor, self.thermal_resistance, self.heat_capacity)
        coupling = 1.0 / self.thermal_resistance  # 0 where R is inf
        j42 = factor * coupling / self.housing_heat_capacity
        j44 = -(coupling + 1.0 / self.housing_resistance) / self.housing_heat_capacity * ones
        return j24, j42, j44

    def jacobian_matrix(self, y: FloatArray) -> FloatArray:
        """The full Jacobian of one segment (n = 1) at a state of shape (rows,) or (rows, 1)."""
        column = np.reshape(y, (self.rows, 1))
        j10, j11, j12, j21, j22, j31, j32 = (float(np.ravel(j)[0]) for j in self.jacobian(column))
        if self.two_node:
            j24, j42, j44 = (float(np.ravel(j)[0]) for j in self.housing_jacobian(column))
            return np.array(
                [
                    [0.0, 1.0, 0.0, 0.0, 0.0],
                    [j10, j11, j12, 0.0, 0.0],
                    [0.0, j21, j22, 0.0, j24],
                    [0.0, j31, j32, 0.0, 0.0],
                    [0.0, 0.0, j42, 0.0, j44],
                ]
            )
        return np.array(
            [
                [0.0, 1.0, 0.0, 0.0],
                [j10, j11, j12, 0.0],
                [0.0, j21, j22, 0.0],
                [0.0, j31, j32, 0.0],
            ]
        )
