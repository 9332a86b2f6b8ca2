"""The dynamic deployment problem: the quasi-static problem plus inertia, stiction and more.

:class:`DynamicProblem` *is a* :class:`~ecdsim.solvers.QuasiStaticProblem` (same spring
breakpoints, total friction and damping rate, so the ``paper`` and ``exact`` methods
solve its quasi-static limit unchanged) with the extra per-case arrays the ``dynamic``
method needs. :func:`dynamic_problem` builds it from a system, its ECD state and a
:class:`~ecdsim.dynamics.params.DynamicParameters`, calling the same model objects and
physics functions as the quasi-static path.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass, field, fields
from functools import cache
from typing import Any

import numpy as np

from ecdsim._types import (
    FloatArray,
    any_true,
    broadcast,
    joint_shape,
    one_case_rows,
    one_case_views,
)
from ecdsim.dynamics.damping import EddyLaw, KlossEddy, LinearEddy
from ecdsim.dynamics.kernel import effects as registry
from ecdsim.dynamics.mesh_limits import DynamicDomainError as DynamicDomainError
from ecdsim.dynamics.mesh_limits import _check_compliant
from ecdsim.dynamics.params import DynamicParameters, Thermal
from ecdsim.model import DeploymentSystem, EcdState
from ecdsim.physics import mechanics, rolloff
from ecdsim.solvers.base import QuasiStaticProblem

_QS_FIELDS = ("angles", "torques", "friction", "damping_rate")


@cache
def _field_names(kind: type) -> tuple[str, ...]:
    """The field names of a dataclass, looked up once per class (``fields()`` costs a
    microsecond per call, and every problem asks it of its eddy law)."""
    return tuple(f.name for f in fields(kind))


def _shape(value: float | FloatArray) -> tuple[int, ...]:
    """``np.shape(value)``; at once for a float (np.shape makes it an array first)."""
    return () if type(value) is float else np.shape(value)


@dataclass(frozen=True, kw_only=True)
class DynamicProblem(QuasiStaticProblem):
    """The full deployment dynamics at the input (slow) shaft, for a batch of cases.

    Engaged: ``(J_L + J_D) phi'' = T_spring(phi) - sign(phi') (FECD + FS) - M_d``, with
    ``M_d = N * (T_eddy(N phi', T_d) + BG * N * phi')`` the ECD damping torque (equal to
    ``BECD_T * phi'`` for the linear law at ambient temperature). During the lost motion
    the load moves alone: ``J_L phi'' = T_spring(phi) - sign(phi') FS``.

    Attributes (beyond those of QuasiStaticProblem; all broadcast to the batch shape)
    ----------
    load_inertia : J_L [kg*m^2]
    damper_inertia : J_D, damper rotor and gearbox reflected to the input [kg*m^2]
    ecd_friction : FECD_T (Eq. 4) [N*m]
    system_friction : FS_T [N*m]
    static_friction_factor : breakaway over kinetic friction of the ECD, FECD_T [-]
    system_static_friction_factor : breakaway over kinetic system friction FS_T [-]
    restitution : end-stop coefficient of restitution [-]
    lost_motion : gear lost motion at the input shaft [rad]
    initial_angle : deployed angle at release [rad]
    initial_speed : load speed at release [rad/s]
    ambient_temperature : the case's temperature T, and the damper's at release [degC]
    gear_ratio : N [-]
    gearbox_damping_rate : BG at the high-speed shaft [N*m*s/rad]
    heat_capacity : damper heat capacity [J/K]; inf when self-heating is not modelled
    thermal_resistance : damper to ambient [K/W]; inf for adiabatic
    stribeck_speed : w_St, Stribeck speed at the input shaft [rad/s]; inf (the default)
        for none (kinetic friction independent of speed, as before)
    gear_stiffness : c, torsional stiffness of the gear mesh at the input shaft
        [N*m/rad]; inf (the default) for a rigid mesh (plastic engagement)
    gear_mesh_damping : d, damping of the mesh in contact at the input shaft [N*m*s/rad]
    housing_heat_capacity : C_h of the two-node heating [J/K]; inf for one node
    housing_thermal_resistance : R_he, housing to the environment [K/W]; inf adiabatic
    initial_rotor_rise : damper (rotor) temperature above T at release [K]
    initial_housing_rise : housing temperature above T at release [K]
    forward_efficiency : eta_f of a lossy mesh [-]; 1 (the default) for an ideal gear.
        ``damping_rate`` and ``ecd_friction`` already include it (Eq. 3-4 / eta_f)
    backward_efficiency : eta_b of a lossy mesh, while the damper side drives [-]; 1
    eddy : the damper's eddy-current law (linear Eq. 1 or roll-off)
    resistance : a ``[load] resistive_table``'s torque at each breakpoint [N*m] (the
        breakpoints' shape); ``torques`` are the spring's less it. None without a table
    thermal : True when self-heating is modelled
    two_node : True when the housing is a heat capacity of its own
    stop_time : end of the simulated interval [s]
    rtol : relative tolerance of the integrator for nonlinear segments [-]
    integrator : integrator for nonlinear segments ("RODAS4" batched, or a solve_ivp method)
    max_events : event limit per run
    effects : the registered effects' parameters by name, each broadcast to the batch
        (:mod:`ecdsim.dynamics.kernel.effects`); empty without any
    """

    load_inertia: FloatArray
    damper_inertia: FloatArray
    ecd_friction: FloatArray
    system_friction: FloatArray
    static_friction_factor: FloatArray
    system_static_friction_factor: FloatArray
    restitution: FloatArray
    lost_motion: FloatArray
    initial_angle: FloatArray
    initial_speed: FloatArray
    ambient_temperature: FloatArray
    gear_ratio: FloatArray
    gearbox_damping_rate: FloatArray
    heat_capacity: FloatArray
    thermal_resistance: FloatArray
    eddy: EddyLaw
    stribeck_speed: FloatArray = field(default_factory=lambda: np.asarray(math.inf))
    gear_stiffness: FloatArray = field(default_factory=lambda: np.asarray(math.inf))
    gear_mesh_damping: FloatArray = field(default_factory=lambda: np.asarray(0.0))
    housing_heat_capacity: FloatArray = field(default_factory=lambda: np.asarray(math.inf))
    housing_thermal_resistance: FloatArray = field(default_factory=lambda: np.asarray(math.inf))
    initial_rotor_rise: FloatArray = field(default_factory=lambda: np.asarray(0.0))
    initial_housing_rise: FloatArray = field(default_factory=lambda: np.asarray(0.0))
    forward_efficiency: FloatArray = field(default_factory=lambda: np.asarray(1.0))
    backward_efficiency: FloatArray = field(default_factory=lambda: np.asarray(1.0))
    resistance: FloatArray | None = None
    thermal: bool = False
    two_node: bool = False
    stop_time: float = math.inf
    rtol: float = 1e-8
    integrator: str = "RODAS4"
    max_events: int = 10_000
    effects: Mapping[str, FloatArray] = field(default_factory=dict)

    def __post_init__(self) -> None:
        own = [np.asarray(getattr(self, name), dtype=float) for name in _CASE_FIELDS]
        registered = {k: np.asarray(v, dtype=float) for k, v in self.effects.items()}
        angles = np.asarray(self.angles, dtype=float)
        friction = np.asarray(self.friction, dtype=float)
        damping = np.asarray(self.damping_rate, dtype=float)
        eddy = self.eddy
        batch = joint_shape(
            angles.shape[1:],
            np.shape(self.torques)[1:],
            friction.shape,
            damping.shape,
            *(value.shape for value in own),
            *(value.shape for value in registered.values()),
            # The eddy law's own arrays (a Monte Carlo batch of roll-off peak speeds).
            *(_shape(getattr(eddy, name)) for name in _field_names(type(eddy))),
        )
        if math.prod(batch) == 1:
            # One case (a single deployment): the same read-only views of the batch shape
            # as broadcast() makes, from one array for all the fields.
            friction, damping, *own = one_case_views([friction, damping, *own], batch)
        else:
            friction = broadcast(friction, batch)
            damping = broadcast(damping, batch)
            own = [broadcast(value, batch) for value in own]
        # Widen the quasi-static fields to the joint batch first, then let the base class
        # align the breakpoint arrays with them.
        object.__setattr__(self, "friction", friction)
        object.__setattr__(self, "damping_rate", damping)
        super().__post_init__()
        for name, value in zip(_CASE_FIELDS, own, strict=True):
            object.__setattr__(self, name, value)
        effects = {k: broadcast(v, batch) for k, v in registered.items()}
        object.__setattr__(self, "effects", effects)

    @property
    def nonlinear(self) -> bool:
        """True when engaged segments need numerical integration."""
        return self.thermal or self.eddy.name != "linear"

    @property
    def lossy(self) -> bool:
        """True when some case's gear has a mesh efficiency below 1 (issue 16 item 5)."""
        return any_true(self.forward_efficiency != 1.0) or any_true(self.backward_efficiency != 1.0)

    @property
    def stribeck(self) -> bool:
        """True when some case's sliding friction depends on speed (a Stribeck speed)."""
        return any_true(np.isfinite(self.stribeck_speed))

    @property
    def compliant(self) -> bool:
        """True when some case has a compliant gear mesh (compliant backlash)."""
        return any_true(np.isfinite(self.gear_stiffness))

    @property
    def total_inertia(self) -> FloatArray:
        """J_L + J_D [kg*m^2]."""
        return np.asarray(self.load_inertia + self.damper_inertia)


# Per-case array fields of DynamicProblem, in its order (broadcast to the batch shape
# together): its own FloatArray fields.
_CASE_FIELDS = tuple(
    f.name for f in fields(DynamicProblem) if f.type == "FloatArray" and f.name not in _QS_FIELDS
)


def dynamic_problem(
    system: DeploymentSystem,
    ecd: EcdState,
    temperatures: FloatArray,
    base: QuasiStaticProblem,
    system_friction: FloatArray,
    params: DynamicParameters,
) -> DynamicProblem:
    """The dynamic problem of ``system`` at ``temperatures`` [degC].

    ``ecd``, ``base`` and ``system_friction`` are the quasi-static quantities that
    :func:`ecdsim.deployment.build_problem` made for the same temperatures; they are
    reused, never recomputed. Raises ValueError where a parameter leaves its domain (the
    message names the field).
    """
    n = ecd.gear_ratio
    reflected: float | FloatArray | None = _one_case_reflected(params, n)
    if reflected is None:
        reflected = mechanics.reflect_inertia_to_input(
            np.asarray(params.rotor_inertia, float) + np.asarray(params.gearbox_inertia, float), n
        )
    eddy = _eddy_law(system.ecd.damper, params, temperatures)
    _check_start(params, base, eddy, temperatures)
    lossy = _differs(ecd.forward_efficiency, 1.0) or _differs(ecd.backward_efficiency, 1.0)
    if lossy and params.stribeck_speed is not None:
        # The Stribeck excess mixes the ECD's friction (through the mesh) with the
        # system's (not): its mesh loss is not separated yet (docs/dynamics.md).
        raise DynamicDomainError(
            "gearbox.efficiency",
            "the dynamic method takes a lossy gear without damper.stribeck_speed only",
        )
    if params.gear_stiffness is not None:
        _check_compliant(params, reflected, base.damping_rate, lossy, base.has_gravity)
    case = _case_fields(params, ecd, reflected, system_friction, temperatures)
    case["lost_motion"] = system.ecd.gearbox.lost_motion
    thermal = params.thermal
    resistive = system.load.resistance
    settings: dict[str, Any] = {
        "eddy": eddy,
        "resistance": None
        if resistive is None
        else np.asarray(resistive.torque_at(base.angles, temperatures), dtype=float),
        "thermal": thermal is not None,
        "two_node": thermal is not None and thermal.housing_heat_capacity is not None,
        "stop_time": params.stop_time,
        "rtol": params.rtol,
        "integrator": params.integrator,
        "max_events": params.max_events,
        "effects": dict(params.effects),
    }
    one = None if params.effects else _one_case_problem(base, case, settings)
    if one is not None:
        return one
    return DynamicProblem(
        angles=base.angles,
        torques=base.torques,
        friction=base.friction,
        damping_rate=base.damping_rate,
        **case,
        **settings,
    )


def _eddy_law(damper: Any, params: DynamicParameters, temperatures: FloatArray) -> EddyLaw:
    """The damper's eddy law: Eq. 1's linear law, or the Kloss roll-off (checked)."""
    if params.rolloff is None:
        return LinearEddy(
            damper.damping_rate,
            damper.reference_temperature,
            damper.damping_temperature_coefficient,
        )
    peak_speed = params.rolloff.peak_speed
    alpha = params.rolloff.resistivity_coefficient
    if _peak_speed_not_positive(temperatures, peak_speed, alpha, damper.reference_temperature):
        raise DynamicDomainError(
            "damper.rolloff.resistivity_coefficient",
            "the peak speed omega_peak(T) is <= 0 at an analysis temperature; the "
            "resistivity law does not reach that far",
        )
    if params.thermal is not None and _below_zero(alpha):
        # Heating drives omega_peak = omega_peak_ref (1 + alpha (T - T_ref)) towards 0
        # and the low-speed damping BD / (1 + alpha (T - T_ref)) to infinity: the
        # damper would lock the load short of the end, approached without end.
        raise DynamicDomainError(
            "damper.rolloff.resistivity_coefficient",
            f"must be >= 0 with self-heating (got {float(np.min(alpha)):.6g} /K): the "
            "Kloss law's low-speed damping BD / (1 + alpha (T - T_ref)) grows without "
            "bound as the damper heats towards T_ref - 1/alpha (conductors have "
            "alpha > 0; copper 0.0039 /K)",
        )
    peak_torque = rolloff.peak_torque_from_damping(damper.damping_rate, peak_speed)
    return KlossEddy(peak_torque, peak_speed, alpha, damper.reference_temperature)


def _check_start(
    params: DynamicParameters, base: QuasiStaticProblem, eddy: EddyLaw, temperatures: FloatArray
) -> None:
    """The release angle lies on the travel; a warm start below the damping law's zero."""
    travel = np.asarray(base.travel)
    start = np.asarray(params.initial_angle, dtype=float)
    if start.size == 1 and travel.size == 1:  # one case: the same test on the numbers
        outside = start.item() < 0.0 or start.item() >= travel.item()
    else:
        outside = any_true(start < 0.0) or any_true(start >= travel)
    if outside:
        raise DynamicDomainError(
            "initial.angle",
            f"must be >= 0 and below the travel ({float(np.min(travel)):.6g} rad), got "
            f"{float(np.max(start)):.6g} rad",
        )
    thermal = params.thermal
    if thermal is not None and _differs(thermal.initial_rotor_rise, 0.0):
        # A warm start (repeated deployments) must lie below the damping law's zero.
        warm = eddy.factor(np.asarray(temperatures, float) + thermal.initial_rotor_rise)
        if any_true(np.asarray(warm <= 0.0)):
            raise DynamicDomainError(
                "damper.thermal.initial_rotor_rise",
                "puts the damper at or beyond the temperature where its damping law reaches zero",
            )


def _case_fields(
    params: DynamicParameters,
    ecd: EcdState,
    reflected: float | FloatArray,
    system_friction: FloatArray,
    temperatures: FloatArray,
) -> dict[str, Any]:
    """The per-case fields of :class:`DynamicProblem` (the lost motion aside)."""
    thermal = params.thermal
    static = params.system_static_friction_factor
    return {
        "load_inertia": params.load_inertia,
        "damper_inertia": reflected,
        "ecd_friction": ecd.ecd_friction,
        "system_friction": system_friction,
        "static_friction_factor": params.static_friction_factor,
        "system_static_friction_factor": params.static_friction_factor
        if static is None
        else static,
        "restitution": params.restitution,
        "initial_angle": np.asarray(params.initial_angle, dtype=float),
        "initial_speed": params.initial_speed,
        "ambient_temperature": temperatures,
        "gear_ratio": ecd.gear_ratio,
        "gearbox_damping_rate": ecd.gearbox_damping_rate,
        "heat_capacity": math.inf if thermal is None else thermal.heat_capacity,
        "thermal_resistance": math.inf if thermal is None else thermal.thermal_resistance,
        "stribeck_speed": math.inf if params.stribeck_speed is None else params.stribeck_speed,
        "gear_stiffness": math.inf if params.gear_stiffness is None else params.gear_stiffness,
        "gear_mesh_damping": 0.0 if params.gear_mesh_damping is None else params.gear_mesh_damping,
        **_two_node_fields(thermal),
        "forward_efficiency": ecd.forward_efficiency,
        "backward_efficiency": ecd.backward_efficiency,
    }


# Every field of DynamicProblem by where _one_case_problem takes it from: the base
# problem's breakpoints, friction and damping; the per-case numbers; the settings. A
# field added to the class must be added here too (tests/test_fast_paths.py).
_BASE_FIELDS = _QS_FIELDS
# The registered effects' parameters that are fields (gravity's): predict sets them.
_REGISTERED_FIELDS = tuple(p.name for p in registry.PARAMETERS if p.config is None)
_SETTING_FIELDS = (
    "eddy",
    "resistance",
    "thermal",
    "two_node",
    "stop_time",
    "rtol",
    "integrator",
    "max_events",
    "effects",  # empty: a problem with registered effects takes the general path
)


def _one_case_problem(
    base: QuasiStaticProblem, case: dict[str, Any], settings: dict[str, Any]
) -> DynamicProblem | None:
    """``DynamicProblem(**base fields, **case, **settings)`` for one case, or None.

    The same problem, field for field (values, shapes, dtypes, read-only views), as the
    dataclass's ``__init__`` and ``__post_init__`` make of these arguments, built without
    them: ``base`` is a normalized QuasiStaticProblem already (aligned read-only float64
    fields), so for one case the general path only reads every per-case value's one
    number into one array and hands out its rows (``one_case_views``), which is what this
    does directly. A single deployment saves the dataclass machinery (some 20 us; issue
    13, single cases). None, for the general path, when ``base`` holds several cases or a
    value would widen its batch shape (more axes, or more than one number).
    """
    batch = base.friction.shape
    if math.prod(batch) != 1:
        return None
    depth = len(batch)
    eddy: EddyLaw = settings["eddy"]
    for name in _field_names(type(eddy)):
        value = getattr(eddy, name)
        if type(value) is not float:  # a float is one number of no axes
            shape = np.shape(value)
            if len(shape) > depth or math.prod(shape) != 1:
                return None
    # The general path's order: friction, damping_rate, then _CASE_FIELDS.
    numbers = [base.friction.item(), base.damping_rate.item()]
    append = numbers.append  # (bound once: 24 calls)
    for value in map(case.__getitem__, _CASE_FIELDS):
        if type(value) is not float:  # a float is its own item()
            array = value if type(value) is np.ndarray else np.asarray(value, dtype=float)
            if array.ndim > depth or array.size != 1:
                return None
            # item() of an integer or boolean array is an int: float() is asarray's cast.
            value = float(array.item())
        append(value)
    friction, damping, *rows = one_case_rows(numbers, batch)
    problem = object.__new__(DynamicProblem)
    # A frozen dataclass without slots: its fields live in the instance __dict__.
    state = vars(problem)
    state.update(
        angles=base.angles,
        torques=base.torques,
        friction=friction,
        damping_rate=damping,
    )
    # dynamic_problem never passes gravity on (predict adds it with replace()).
    state.update(dict.fromkeys(_REGISTERED_FIELDS))
    state.update(zip(_CASE_FIELDS, rows, strict=True))
    state.update(settings)
    return problem


def _one_case_reflected(params: DynamicParameters, gear_ratio: FloatArray) -> float | None:
    """``reflect_inertia_to_input(J_rotor + J_gearbox, N)`` in floats, or None.

    ``(J_rotor + J_gearbox) N N`` (mechanics.reflect_inertia_to_input, Wittenburg 2008,
    3.3) in its order of operations, the same bits as its NumPy arithmetic, for float
    inertias and a 0-d gear ratio (the one-case Ecd.at's), whose NumPy answer is a 0-d
    array: DynamicProblem reads the float as that array (issue 13, single cases). None,
    for the NumPy path, for any other shape or type, or an answer that is not finite
    (NumPy's overflow warning).
    """
    rotor, gearbox = params.rotor_inertia, params.gearbox_inertia
    if type(rotor) is not float or type(gearbox) is not float or gear_ratio.shape != ():
        return None
    n = float(gear_ratio.item())
    reflected = (rotor + gearbox) * n * n
    return reflected if math.isfinite(reflected) else None


def _peak_speed_not_positive(
    temperatures: FloatArray,
    peak_speed: float | FloatArray,
    coefficient: float | FloatArray,
    reference: float,
) -> bool:
    """True where ``rolloff.peak_speed_at`` is <= 0 at some analysis temperature (NaN
    is not <= 0)."""
    with np.errstate(over="ignore", invalid="ignore"):
        peaks = rolloff.peak_speed_at(temperatures, peak_speed, coefficient, reference)
    return any_true(np.asarray(peaks <= 0.0))


def _differs(value: float | FloatArray, number: float) -> bool:
    """``any_true(np.asarray(value) != number)``; a float or one element compared as a
    Python float (NaN differs from everything in both), without NumPy's comparison
    (issue 13, single cases)."""
    if type(value) is float:
        return value != number
    array = np.asarray(value)
    if array.size == 1:
        return bool(array.item() != number)
    return any_true(np.asarray(array != number))


def _below_zero(value: float | FloatArray) -> bool:
    """``any_true(np.asarray(value, dtype=float) < 0)``; a float compared as it is (NaN
    is not below zero in either)."""
    if type(value) is float:
        return value < 0.0
    return any_true(np.asarray(value, dtype=float) < 0.0)


def _two_node_fields(thermal: Thermal | None) -> dict[str, Any]:
    """The housing node and the start temperatures of :class:`DynamicProblem`: the
    one-node defaults without ``Thermal.housing_heat_capacity``."""
    values: dict[str, Any] = {
        "housing_heat_capacity": math.inf,
        "housing_thermal_resistance": math.inf,
        "initial_rotor_rise": 0.0,
        "initial_housing_rise": 0.0,
    }
    if thermal is None:
        return values
    values["initial_rotor_rise"] = thermal.initial_rotor_rise
    values["initial_housing_rise"] = thermal.initial_housing_rise
    if thermal.housing_heat_capacity is not None:
        values["housing_heat_capacity"] = thermal.housing_heat_capacity
        values["housing_thermal_resistance"] = thermal.housing_thermal_resistance
    return values
