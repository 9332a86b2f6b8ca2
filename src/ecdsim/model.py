"""Thin frozen dataclasses that hold an ECD system's parameters and delegate to physics.

Every numeric field is in SI units (temperatures in degC) and may be a float or a NumPy
array; arrays broadcast against the temperatures passed in, so one object can describe a
whole batch of parameter sets (a tolerance study, a catalogue sweep). No formula lives
here that a test cannot reach directly in :mod:`ecdsim.physics`.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Protocol, TypeAlias

import numpy as np

from ecdsim._types import ArrayLike, BoolArray, FloatArray, as_float, joint_shape
from ecdsim.physics import assembly, gearing, gravity, laws, load

Param: TypeAlias = float | FloatArray


class TemperatureLaw(Protocol):
    """A quantity that depends on temperature: FL_T or FS_T in the paper."""

    def __call__(self, temperature: ArrayLike) -> FloatArray:
        """The quantity at temperature T [degC], in its SI unit."""
        ...

    def out_of_range(self, temperature: ArrayLike) -> BoolArray:
        """True where T [degC] lies outside the law's stated validity range."""
        ...

    def describe(self) -> str:
        """A one-line human description of the law."""
        ...


@dataclass(frozen=True)
class LinearTemperatureLaw:
    """``slope * T + at_0c``, the paper's form for FL_T and FS_T (sections 2.3 and 5).

    Attributes
    ----------
    slope : change per kelvin [unit / K]
    at_0c : value at 0 degC [unit]
    """

    slope: Param = 0.0
    at_0c: Param = 0.0

    def __call__(self, temperature: ArrayLike) -> FloatArray:
        """Evaluate the law at T [degC]."""
        return laws.linear_in_temperature(temperature, self.slope, self.at_0c)

    def one_case(self, temperature: float) -> float | None:
        """The law at one temperature T [degC] in Python floats, or None.

        ``slope * T + at_0c`` in :func:`laws.linear_in_temperature`'s order of operations
        (the same bits as its NumPy arithmetic) for float parameters, without its NumPy
        calls on one number (issue 13, single cases). None for array parameters, or an
        answer that is not finite (the NumPy path warns of an overflow).
        """
        slope, at_0c = self.slope, self.at_0c
        if type(slope) is not float or type(at_0c) is not float:
            return None
        value = slope * temperature + at_0c
        return value if math.isfinite(value) else None

    def out_of_range(self, temperature: ArrayLike) -> BoolArray:
        """A linear law has no stated range: never out of range."""
        return np.zeros(np.shape(temperature), dtype=bool)

    def describe(self) -> str:
        """One-line description."""
        return f"linear: {self.slope:g} per K * T + {self.at_0c:g}"


@dataclass(frozen=True)
class TabulatedTemperatureLaw:
    """A measured (T, value) table, interpolated linearly, held at its ends outside.

    Attributes
    ----------
    temperatures : strictly increasing table temperatures [degC]
    values : the quantity at those temperatures [unit]
    """

    temperatures: tuple[float, ...]
    values: tuple[float, ...]

    def __post_init__(self) -> None:
        if len(self.temperatures) != len(self.values) or len(self.temperatures) < 2:
            raise ValueError("a temperature table needs at least two (T, value) points")
        if np.any(np.diff(self.temperatures) <= 0.0):
            raise ValueError("table temperatures must be strictly increasing")

    def __call__(self, temperature: ArrayLike) -> FloatArray:
        """Evaluate the table at T [degC]."""
        return laws.interpolate_table(temperature, self.temperatures, self.values)

    def out_of_range(self, temperature: ArrayLike) -> BoolArray:
        """True outside [first, last] table temperature."""
        return laws.outside_table(temperature, self.temperatures)

    def describe(self) -> str:
        """One-line description."""
        first, last = self.temperatures[0], self.temperatures[-1]
        return f"table of {len(self.temperatures)} points, {first:g} to {last:g} degC"


ZERO_LAW = LinearTemperatureLaw()


@dataclass(frozen=True)
class HighSpeedDamper:
    """The high-speed magnetic damper (paper section 2), parameters at its own shaft.

    Attributes
    ----------
    damping_rate : BD at the reference temperature [N*m*s/rad]
    coulomb_friction : FD [N*m]
    lubrication_friction : FL_T, a temperature law [N*m]
    reference_temperature : temperature at which BD is rated [degC]
    damping_temperature_coefficient : fractional change of BD per kelvin [1/K]
    max_linear_speed : end of the linear range, as a shaft speed [rad/s]; None if unknown
    max_linear_torque : end of the linear range, as an eddy-current torque [N*m]; None if unknown
    """

    damping_rate: Param
    coulomb_friction: Param = 0.0
    lubrication_friction: TemperatureLaw = ZERO_LAW
    reference_temperature: float = 25.0
    damping_temperature_coefficient: Param = -0.004
    max_linear_speed: float | None = None
    max_linear_torque: float | None = None

    def damping_rate_at(self, temperature: ArrayLike) -> FloatArray:
        """BD_T at temperature T [degC] (Eq. 1, first term) [N*m*s/rad]."""
        return assembly.damper_damping_rate(
            self.damping_rate,
            temperature,
            self.reference_temperature,
            self.damping_temperature_coefficient,
        )


@dataclass(frozen=True)
class GearEfficiency:
    """Mesh efficiency of a lossy gear (issue 16 item 5; Modelica's LossyGear).

    ``forward`` applies while the load drives the damper (power from the slow input to the
    fast shaft, every deployment), ``backward`` while the damper side's inertia drives the
    load (an overrunning rotor, a rebound): :mod:`ecdsim.physics.gearing`.

    Attributes
    ----------
    forward : eta_f, in (0, 1] [-]
    backward : eta_b, in (0, 1] [-]
    """

    forward: Param = 1.0
    backward: Param = 1.0


@dataclass(frozen=True)
class Gearbox:
    """The step-up gearbox (paper section 3), damping and friction at the high-speed shaft.

    Give the gearbox damping either as an absolute ``damping_rate`` or as a
    ``damping_fraction`` of the damper's BD (the paper's example: 0.26); the paper holds
    BG constant over temperature (matched CTE, section 3.2).

    Attributes
    ----------
    ratio : N, high-speed turns per input turn [-]
    coulomb_friction : FG [N*m]
    damping_rate : BG [N*m*s/rad], or None to use damping_fraction
    damping_fraction : BG / BD [-], or None to use damping_rate
    lost_motion : gear backlash seen at the input shaft [rad] (reported; used by dynamics)
    efficiency : mesh efficiency forward and back-driven, the alternative to FG; None for
        none (an ideal mesh: Eq. 3-4 as printed)
    """

    ratio: Param
    coulomb_friction: Param = 0.0
    damping_rate: Param | None = None
    damping_fraction: Param | None = None
    lost_motion: float = 0.0
    efficiency: GearEfficiency | None = None

    def __post_init__(self) -> None:
        if (self.damping_rate is None) == (self.damping_fraction is None):
            raise ValueError("give exactly one of gearbox damping_rate and damping_fraction")

    def damping_rate_for(self, damper: HighSpeedDamper) -> FloatArray:
        """BG at the high-speed shaft [N*m*s/rad], resolving a fraction against BD."""
        if self.damping_rate is not None:
            return np.asarray(self.damping_rate, dtype=float)
        fraction = np.asarray(self.damping_fraction, dtype=float)
        return as_float(fraction * np.asarray(damper.damping_rate, dtype=float))


@dataclass(frozen=True)
class EcdState:
    """The ECD's component values at given temperatures; every field broadcasts.

    Attributes
    ----------
    temperature : T [degC]
    damper_damping_rate : BD_T [N*m*s/rad]
    gearbox_damping_rate : BG [N*m*s/rad]
    total_damping_rate : BT_T = BD_T + BG (Eq. 1) [N*m*s/rad]
    damper_friction : FD [N*m]
    lubrication_friction : FL_T [N*m]
    gearbox_friction : FG [N*m]
    total_friction : FT_T (Eq. 2) [N*m]
    ecd_damping_rate : BECD_T at the input shaft (Eq. 3) [N*m*s/rad]
    ecd_friction : FECD_T at the input shaft (Eq. 4) [N*m]
    gear_ratio : N [-]
    forward_efficiency : eta_f of a lossy mesh (1: ideal); BECD_T and FECD_T include it
    backward_efficiency : eta_b of a lossy mesh (1: ideal), for back-driven motion
    """

    temperature: FloatArray
    damper_damping_rate: FloatArray
    gearbox_damping_rate: FloatArray
    total_damping_rate: FloatArray
    damper_friction: FloatArray
    lubrication_friction: FloatArray
    gearbox_friction: FloatArray
    total_friction: FloatArray
    ecd_damping_rate: FloatArray
    ecd_friction: FloatArray
    gear_ratio: FloatArray
    forward_efficiency: FloatArray = field(default_factory=lambda: np.asarray(1.0))
    backward_efficiency: FloatArray = field(default_factory=lambda: np.asarray(1.0))

    def input_speed(self, torque: ArrayLike) -> FloatArray:
        """Steady input speed under a constant input torque [N*m] (Eq. 5) [rad/s]."""
        return assembly.input_speed(torque, self.ecd_friction, self.ecd_damping_rate)

    def dynamic_damping_rate(self, torque: ArrayLike) -> FloatArray:
        """CDA's dynamic damping rate at input torque [N*m] (Eq. 6) [N*m*s/rad]."""
        return assembly.dynamic_damping_rate(torque, self.input_speed(torque))


@dataclass(frozen=True)
class Ecd:
    """An ECD assembly: a high-speed damper behind a step-up gearbox (paper section 4)."""

    damper: HighSpeedDamper
    gearbox: Gearbox

    def at(self, temperature: ArrayLike) -> EcdState:
        """Evaluate Eq. 1-4 at temperature(s) T [degC]."""
        t = np.asarray(temperature, dtype=float)
        if t.size == 1:
            state = self._one_case_at(t)
            if state is not None:
                return state
        bd_t = self.damper.damping_rate_at(t)
        bg = self.gearbox.damping_rate_for(self.damper)
        fd = np.asarray(self.damper.coulomb_friction, dtype=float)
        fl = self.damper.lubrication_friction(t)
        fg = np.asarray(self.gearbox.coulomb_friction, dtype=float)
        bt = assembly.total_damping_rate(bd_t, bg)
        ft = assembly.total_friction(fd, fl, fg)
        n = np.asarray(self.gearbox.ratio, dtype=float)
        efficiency = self.gearbox.efficiency
        ideal = np.asarray(1.0)
        eta_f = ideal if efficiency is None else np.asarray(efficiency.forward, dtype=float)
        eta_b = ideal if efficiency is None else np.asarray(efficiency.backward, dtype=float)
        if efficiency is None:
            ecd_damping = assembly.refer_damping_to_input(bt, n)
            ecd_friction = assembly.refer_friction_to_input(ft, n)
        else:
            # A lossy mesh driven forward (issue 16 item 5): Eq. 3-4 divided by eta_f.
            ecd_damping = gearing.refer_damping_through_mesh(bt, n, eta_f)
            ecd_friction = gearing.refer_friction_through_mesh(ft, n, eta_f)
        return EcdState(
            temperature=t,
            damper_damping_rate=bd_t,
            gearbox_damping_rate=bg,
            total_damping_rate=bt,
            damper_friction=fd,
            lubrication_friction=fl,
            gearbox_friction=fg,
            total_friction=ft,
            ecd_damping_rate=ecd_damping,
            ecd_friction=ecd_friction,
            gear_ratio=n,
            forward_efficiency=eta_f,
            backward_efficiency=eta_b,
        )

    def _one_case_at(self, t: FloatArray) -> EcdState | None:
        """:meth:`at` of one temperature in Python floats, or None for the general path.

        The same state, field for field (values, shapes, dtypes, writeable arrays), for
        the common assembly: every parameter a float, a linear lubrication law, an ideal
        gear. Eq. 1-4 are the formulas of ``physics.assembly`` and ``physics.laws``
        written out in the same order of operations (IEEE doubles: the same bits as
        NumPy's elementwise arithmetic); a single deployment saves the NumPy calls on
        one-element arrays (about 5 us; issue 13, single cases). A result that is not
        finite takes the general path, which reports an overflow as NumPy does.
        """
        damper, gearbox = self.damper, self.gearbox
        law = damper.lubrication_friction
        if type(law) is not LinearTemperatureLaw or gearbox.efficiency is not None:
            return None
        bg_given = gearbox.damping_rate  # BG, or a fraction of BD (damping_rate_for)
        values = (
            damper.damping_rate,
            damper.damping_temperature_coefficient,
            damper.reference_temperature,
            damper.coulomb_friction,
            gearbox.coulomb_friction,
            gearbox.ratio,
            bg_given if bg_given is not None else gearbox.damping_fraction,
        )
        # Python floats only (not NumPy scalars, whose arithmetic warns on overflow).
        floats = [value for value in values if type(value) is float]
        if len(floats) != len(values):
            return None
        bd, c, t_ref, fd, fg, n, bg_or_fraction = floats
        temperature = t.item()
        fl = law.one_case(temperature)  # linear_in_temperature; None: not floats or finite
        if fl is None:
            return None
        bd_t = bd * (1.0 + c * (temperature - t_ref))  # damper_damping_rate (Eq. 1)
        bg = bg_or_fraction if bg_given is not None else bg_or_fraction * bd  # damping_rate_for
        bt = bd_t + bg  # total_damping_rate (Eq. 1)
        ft = fd + fl + fg  # total_friction (Eq. 2)
        becd = bt * n * n  # refer_damping_to_input (Eq. 3)
        fecd = ft * n  # refer_friction_to_input (Eq. 4)
        if not math.isfinite(bd_t + fl + bt + ft + becd + fecd):
            return None
        # The temperature-dependent fields have the temperature's shape; the constants
        # are 0-d arrays, as np.asarray makes them in the general path.
        rows = np.array([bd_t, fl, bt, ft, becd, fecd]).reshape((6, *t.shape))
        # Iterating gives the rows as views in C; of a 0-d temperature, NumPy scalars:
        # 0-d views by index then.
        views = list(rows) if t.shape else [rows[i, ...] for i in range(6)]
        bd_a, fl_a, bt_a, ft_a, becd_a, fecd_a = views
        ideal = np.asarray(1.0)
        state = object.__new__(EcdState)
        # EcdState(**these) without the frozen dataclass's __init__ (a field at a time
        # through object.__setattr__): it has no slots and no __post_init__, its fields
        # live in the instance __dict__, and every one is given here
        # (tests/test_fast_paths.py fails on a field added and not set).
        vars(state).update(
            temperature=t,
            damper_damping_rate=bd_a,
            gearbox_damping_rate=np.asarray(bg),
            total_damping_rate=bt_a,
            damper_friction=np.asarray(fd),
            lubrication_friction=fl_a,
            gearbox_friction=np.asarray(fg),
            total_friction=ft_a,
            ecd_damping_rate=becd_a,
            ecd_friction=fecd_a,
            gear_ratio=np.asarray(n),
            forward_efficiency=ideal,
            backward_efficiency=ideal,
        )
        return state


class Spring(Protocol):
    """A spring torque over the travel, as a piecewise-linear table of breakpoints."""

    def breakpoints(
        self, travel: ArrayLike, temperature: ArrayLike
    ) -> tuple[FloatArray, FloatArray]:
        """Deployed angles [rad] and torques [N*m] at the breakpoints, along axis 0."""
        ...

    def torque_at(self, angle: ArrayLike, travel: ArrayLike, temperature: ArrayLike) -> FloatArray:
        """Torque [N*m] at deployed angles ``angle`` [rad] within the travel."""
        ...

    def describe(self) -> str:
        """A one-line human description of the spring."""
        ...


@dataclass(frozen=True)
class LinearSpring:
    """Spring torque linear from ``start_torque`` to ``end_torque`` over the travel (Eq. 7).

    Attributes
    ----------
    start_torque : Ts at the reference temperature [N*m]
    end_torque : Te at the reference temperature [N*m]
    temperature_coefficient : fractional change of torque per kelvin [1/K]
    reference_temperature : temperature at which the torques are given [degC]
    """

    start_torque: Param
    end_torque: Param
    temperature_coefficient: Param = 0.0
    reference_temperature: float = 25.0

    def breakpoints(
        self, travel: ArrayLike, temperature: ArrayLike
    ) -> tuple[FloatArray, FloatArray]:
        """Two breakpoints, (0, Ts) and (travel, Te), scaled for temperature."""
        factor = load.spring_temperature_factor(
            temperature, self.temperature_coefficient, self.reference_temperature
        )
        trav = np.asarray(travel, dtype=float)
        angles = np.empty((2, *trav.shape), dtype=np.float64)
        angles[0] = 0.0  # what np.zeros_like(trav) stacked above trav gives
        angles[1] = trav
        torques = _pair(
            np.asarray(self.start_torque, dtype=float) * factor,
            np.asarray(self.end_torque, dtype=float) * factor,
        )
        return angles, torques

    def one_case_breakpoints(
        self, travel: object, temperature: float
    ) -> tuple[list[float], list[float]] | None:
        """:meth:`breakpoints` of one temperature as Python floats, or None.

        For float parameters and travel: ``[0, travel]`` and ``[Ts f, Te f]`` with
        ``f = 1 + k (T - T_ref)`` (``physics.load.spring_temperature_factor``) in the same
        order of operations, the same bits (issue 13, single cases). None also where a
        torque is not finite.
        """
        values = (
            self.start_torque,
            self.end_torque,
            self.temperature_coefficient,
            self.reference_temperature,
            travel,
        )
        floats = [value for value in values if isinstance(value, float) and type(value) is float]
        if len(floats) != len(values):
            return None
        ts, te, k, t_ref, trav = floats
        factor = 1.0 + k * (temperature - t_ref)
        start, end = ts * factor, te * factor
        if not (math.isfinite(start) and math.isfinite(end)):
            return None  # the array path, which reports an overflow as NumPy does
        return [0.0, trav], [start, end]

    def torque_at(self, angle: ArrayLike, travel: ArrayLike, temperature: ArrayLike) -> FloatArray:
        """Eq. 7 at ``angle``: Ts + (Te - Ts) * angle / travel, scaled for temperature."""
        factor = load.spring_temperature_factor(
            temperature, self.temperature_coefficient, self.reference_temperature
        )
        ts = np.asarray(self.start_torque, dtype=float)
        te = np.asarray(self.end_torque, dtype=float)
        fraction = as_float(angle) / np.asarray(travel, dtype=float)
        return as_float((ts + (te - ts) * fraction) * factor)

    def describe(self) -> str:
        """One-line description."""
        return "linear from start_torque to end_torque (Eq. 7)"


def _pair(first: FloatArray, second: FloatArray) -> FloatArray:
    """``np.stack(np.broadcast_arrays(first, second))``: the two on a new axis 0.

    Filled into one array (two assignments broadcast as ``broadcast_arrays`` would):
    the same values, without the 4 us of NumPy's general stacking that a single
    deployment pays twice per call (issue 13, single cases).
    """
    out = np.empty((2, *joint_shape(first.shape, second.shape)), dtype=np.float64)
    out[0] = first
    out[1] = second
    return out


@dataclass(frozen=True)
class TabulatedSpring:
    """Spring torque interpolated linearly in an (angle, torque) table.

    The table starts at angle 0 and reaches at least the travel; points beyond the travel
    are not used (the torque is interpolated at the travel).

    Attributes
    ----------
    angles : strictly increasing deployed angles, the first 0 [rad]
    torques : spring torque at those angles, at the reference temperature [N*m]
    temperature_coefficient : fractional change of torque per kelvin [1/K]
    reference_temperature : temperature at which the torques are given [degC]
    """

    angles: tuple[float, ...]
    torques: tuple[float, ...]
    temperature_coefficient: Param = 0.0
    reference_temperature: float = 25.0

    def __post_init__(self) -> None:
        if len(self.angles) != len(self.torques) or len(self.angles) < 2:
            raise ValueError("a spring table needs at least two (angle, torque) points")
        if self.angles[0] != 0.0:
            raise ValueError("a spring table must start at angle 0 (the start of travel)")
        if np.any(np.diff(self.angles) <= 0.0):
            raise ValueError("spring table angles must be strictly increasing")

    def breakpoints(
        self, travel: ArrayLike, temperature: ArrayLike
    ) -> tuple[FloatArray, FloatArray]:
        """The table's angles clipped to the travel, torques interpolated there."""
        factor = load.spring_temperature_factor(
            temperature, self.temperature_coefficient, self.reference_temperature
        )
        trav = np.asarray(travel, dtype=float)
        batch_ndim = max(trav.ndim, factor.ndim)  # temperatures may add batch axes
        table = np.asarray(self.angles, dtype=float).reshape((-1,) + (1,) * batch_ndim)
        clipped = np.minimum(table, trav)
        clipped[-1] = trav  # the last breakpoint is the latch, whatever the table's end
        torque = load.tabulated_torque(clipped, self.angles, self.torques)
        angles, torques = np.broadcast_arrays(clipped, torque * factor)
        return np.array(angles), np.array(torques)

    def torque_at(self, angle: ArrayLike, travel: ArrayLike, temperature: ArrayLike) -> FloatArray:
        """The table interpolated at ``angle``, scaled for temperature."""
        factor = load.spring_temperature_factor(
            temperature, self.temperature_coefficient, self.reference_temperature
        )
        return as_float(load.tabulated_torque(angle, self.angles, self.torques) * factor)

    def describe(self) -> str:
        """One-line description."""
        return f"table of {len(self.angles)} (angle, torque) points"


@dataclass(frozen=True)
class ResistiveTable:
    """Resistive torque against deployed angle: harness, cable, blanket, connector.

    Positive opposes deployment; linear between the rows (issue 16 item 1). It is a
    function of the angle alone, like the spring (the elastic part of a harness or
    blanket): a resistance that opposes motion in either direction belongs in
    ``system_friction``.

    Attributes
    ----------
    angles : strictly increasing deployed angles, the first 0 [rad]
    torques : resistive torque at those angles, at the reference temperature [N*m]
    temperature_coefficient : fractional change of torque per kelvin [1/K]
    reference_temperature : temperature at which the torques are given [degC]
    scale : factor on every torque of the table [-] (1; a Monte Carlo tolerance)
    """

    angles: tuple[float, ...]
    torques: tuple[float, ...]
    temperature_coefficient: Param = 0.0
    reference_temperature: float = 25.0
    scale: Param = 1.0

    def __post_init__(self) -> None:
        if len(self.angles) != len(self.torques) or len(self.angles) < 2:
            raise ValueError("a resistive table needs at least two (angle, torque) points")
        if self.angles[0] != 0.0:
            raise ValueError("a resistive table must start at angle 0 (the start of travel)")
        if np.any(np.diff(self.angles) <= 0.0):
            raise ValueError("resistive table angles must be strictly increasing")

    def torque_at(self, angle: ArrayLike, temperature: ArrayLike) -> FloatArray:
        """Resistive torque [N*m] at ``angle`` [rad], interpolated, scaled for T."""
        factor = load.spring_temperature_factor(
            temperature, self.temperature_coefficient, self.reference_temperature
        )
        table = load.tabulated_torque(angle, self.angles, self.torques)
        return as_float(table * factor * np.asarray(self.scale, dtype=float))


@dataclass(frozen=True)
class ResistedSpring:
    """The net drive of a spring less a resistive torque table, itself a :class:`Spring`.

    Both are piecewise linear in the angle, so their difference is piecewise linear on
    the union of their breakpoints and every method that takes a tabulated spring solves
    it as it is: the exact method stays exact, the paper method takes its end values
    (issue 16 item 1).
    """

    spring: Spring
    resistance: ResistiveTable

    def breakpoints(
        self, travel: ArrayLike, temperature: ArrayLike
    ) -> tuple[FloatArray, FloatArray]:
        """The union of both tables' breakpoints within the travel, net torque there."""
        angles, _, _ = self.parts(travel, temperature)
        return angles, as_float(self.torque_at(angles, travel, temperature))

    def parts(
        self, travel: ArrayLike, temperature: ArrayLike
    ) -> tuple[FloatArray, FloatArray, FloatArray]:
        """(angles, spring torque, resistive torque) at the union of the breakpoints.

        The drive and the resistance apart, for the torque margin, which factors the
        resistance as its own kind.
        """
        spring_angles, spring_torques = self.spring.breakpoints(travel, temperature)
        # The full batch shape (parameters and temperatures broadcast), so that every
        # array below has the angle on axis 0 and the same batch axes after it.
        batch = np.broadcast_shapes(spring_angles.shape[1:], spring_torques.shape[1:])
        # Batch axes align from the right, after the angle axis.
        missing = (1,) * (len(batch) - (spring_angles.ndim - 1))
        aligned = spring_angles.reshape(
            (spring_angles.shape[0], *missing, *spring_angles.shape[1:])
        )
        points = np.broadcast_to(aligned, (spring_angles.shape[0], *batch))
        trav = np.broadcast_to(np.asarray(travel, dtype=float), batch)
        table = np.asarray(self.resistance.angles, dtype=float).reshape((-1,) + (1,) * len(batch))
        # Rows beyond the travel fall onto it (zero-length segments, as a clipped spring
        # table has): solvers already take those.
        extra = np.minimum(np.broadcast_to(table, (table.shape[0], *batch)), trav)
        angles = np.sort(np.concatenate([points, extra]), axis=0)
        drive = self.spring.torque_at(angles, travel, temperature)
        resist = self.resistance.torque_at(angles, temperature)
        angles, drive, resist = np.broadcast_arrays(angles, drive, resist)
        return as_float(np.array(angles)), as_float(np.array(drive)), as_float(np.array(resist))

    def torque_at(self, angle: ArrayLike, travel: ArrayLike, temperature: ArrayLike) -> FloatArray:
        """Spring less resistance at ``angle`` [N*m] (angle on axis 0, batch axes after)."""
        return as_float(
            self.spring.torque_at(angle, travel, temperature)
            - self.resistance.torque_at(angle, temperature)
        )

    def describe(self) -> str:
        """One-line description."""
        return (
            f"{self.spring.describe()}, less a resistive table of "
            f"{len(self.resistance.angles)} (angle, torque) points"
        )


@dataclass(frozen=True)
class Gravity:
    """Gravity on the deployed mass in a ground test (issue 16 item 2; docs/model.md).

    The torque about the hinge, opposing deployment positive, is
    ``m g r (1 - offload) sin(theta_0 + phi)`` (:mod:`ecdsim.physics.gravity`).

    Attributes
    ----------
    mass : deployed mass m [kg]
    cg_radius : centre of gravity's distance from the hinge axis r [m]
    release_angle : theta_0, from the downward vertical to the hinge-to-CG line at
        release, positive in the direction of deployment [rad]
    offload : fraction of the weight carried by the ground-support equipment [-]
    """

    mass: Param
    cg_radius: Param
    release_angle: Param
    offload: Param = 0.0

    @property
    def amplitude(self) -> FloatArray:
        """W = m g r (1 - offload) [N*m]."""
        return gravity.gravity_amplitude(self.mass, self.cg_radius, self.offload)

    def torque_at(self, angle: ArrayLike) -> FloatArray:
        """Gravity torque at deployed angle phi [N*m], opposing deployment positive."""
        return as_float(
            gravity.gravity_torque(as_float(angle), self.amplitude, as_float(self.release_angle))
        )

    def describe(self) -> str:
        """One-line description."""
        return (
            f"gravity on {np.max(self.mass):g} kg at {np.max(self.cg_radius):g} m, "
            f"{np.max(self.offload) * 100:g} % offloaded"
        )


@dataclass(frozen=True)
class Load:
    """The deployment load seen by the ECD's input shaft (paper section 5).

    Attributes
    ----------
    spring : the driving spring torque over the travel
    travel : deployment angle, delta_theta [rad]
    system_friction : FS_T, hinge and harness friction, a temperature law [N*m]
    resistance : resistive torque against angle (harness, blanket), None for none
    gravity : gravity on the deployed mass in a ground test, None for flight (0 g)
    """

    spring: Spring
    travel: Param
    system_friction: TemperatureLaw = ZERO_LAW
    resistance: ResistiveTable | None = None
    # Gravity in a ground test (issue 16 item 2); None = flight (0 g), today's model.
    gravity: Gravity | None = None

    @property
    def drive(self) -> Spring:
        """The net driving torque over the travel: the spring, less the resistance."""
        if self.resistance is None:
            return self.spring
        return ResistedSpring(self.spring, self.resistance)


@dataclass(frozen=True)
class DeploymentSystem:
    """A spring-driven deployment slowed by an ECD: the full quasi-static model."""

    ecd: Ecd
    load: Load
    name: str = field(default="deployment")
