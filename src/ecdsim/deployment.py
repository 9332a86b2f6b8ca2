"""Predict a deployment over temperature: the system layer over the solvers.

:func:`predict` evaluates the ECD (Eq. 1-4) and the load at each temperature, runs each
requested solver on the same quasi-static problem, checks the damper's linear range,
stalls and table ranges, and returns a :class:`Prediction`. It never prints; warnings are
structured :class:`ModelWarning` records in the result.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, field, replace
from typing import Any

import numpy as np

from ecdsim._types import (
    ArrayLike,
    BoolArray,
    FloatArray,
    all_true,
    any_true,
    broadcast,
    joint_shape,
)
from ecdsim._version import __version__
from ecdsim.dynamics.params import DynamicParameters
from ecdsim.dynamics.problem import DynamicDomainError, DynamicProblem, dynamic_problem
from ecdsim.methods import SOLVERS
from ecdsim.model import DeploymentSystem, EcdState, LinearSpring, LinearTemperatureLaw
from ecdsim.physics import mechanics
from ecdsim.physics.assembly import damper_torque
from ecdsim.physics.gravity import STANDARD_GRAVITY
from ecdsim.solvers import DeploymentSolution, QuasiStaticProblem, Trajectory
from ecdsim.solvers.base import one_case_problem, packed_problem

DEFAULT_METHODS = ("paper", "exact")


class ModelDomainError(ValueError):
    """The model cannot be evaluated for these inputs (for example damping <= 0 at T).

    ``key`` names the config field that leads there, for the one-line user message.
    """

    def __init__(self, key: str, message: str) -> None:
        super().__init__(f"{key}: {message}")
        self.key = key


@dataclass(frozen=True)
class ModelWarning:
    """A non-fatal finding about one case: a flag with a readable message.

    Attributes
    ----------
    code : machine-readable kind ("stall", "linear_range_speed", ...)
    message : one readable sentence
    temperature_C : the case's temperature [degC], None if not specific to one
    method : the solver concerned, None if not specific to one
    """

    code: str
    message: str
    temperature_C: float | None = None
    method: str | None = None

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready form."""
        return {
            "code": self.code,
            "message": self.message,
            "temperature_C": self.temperature_C,
            "method": self.method,
        }


@dataclass(frozen=True)
class Prediction:
    """Deployment predictions for one system over temperatures, by each method.

    Arrays have the batch shape of the temperatures broadcast against the parameters.

    Attributes
    ----------
    system : the system that was solved
    temperatures : T [degC]
    ecd : the ECD's component values at T (Eq. 1-4)
    system_friction : FS_T [N*m]
    problem : the quasi-static problem every method solved
    solutions : one solution per method name
    warnings : findings (stall, linear range, table extrapolation, negative friction)
    """

    system: DeploymentSystem
    temperatures: FloatArray
    ecd: EcdState
    system_friction: FloatArray
    problem: QuasiStaticProblem
    solutions: dict[str, DeploymentSolution]
    warnings: list[ModelWarning] = field(default_factory=list)
    # With [load.gravity]: the same system in flight (0 g), for the side-by-side output
    # (:func:`with_flight`); None otherwise.
    flight: Prediction | None = None

    @property
    def resistance(self) -> FloatArray | None:
        """The ``[load] resistive_table`` torque at each breakpoint of the problem [N*m];
        None without one. The problem's torques are the net drive (spring less this)."""
        resistance = self.system.load.resistance
        if resistance is None:
            return None
        return resistance.torque_at(self.problem.angles, self.temperatures)

    def trajectory(self, method: str, times: ArrayLike) -> Trajectory:
        """Angle and speed against time [s] by one method."""
        solution = self.solutions.get(method)
        kept = solution.trajectory(times) if solution is not None else None
        return kept if kept is not None else SOLVERS[method].trajectory(self.problem, times)

    def time_difference(self, method: str = "paper", reference: str = "exact") -> FloatArray:
        """Deployment time by ``method`` minus that by ``reference`` [s]; NaN-free.

        Where either method stalls the difference is reported as 0 if both stall (they
        agree) and is not defined otherwise; both stall together in ecdsim, so it is 0.
        """
        a = self.solutions[method].deployment_time
        b = self.solutions[reference].deployment_time
        both_finite = np.isfinite(a) & np.isfinite(b)
        return np.where(
            both_finite, np.where(both_finite, a, 0.0) - np.where(both_finite, b, 0.0), 0.0
        )

    def to_dict(self) -> dict[str, Any]:
        """The stable JSON document of ``ecdsim deploy --json`` (see ``docs/json.md``)."""
        if self.temperatures.ndim != 1 or self.problem.batch_shape != self.temperatures.shape:
            raise ValueError("to_dict() needs one case per temperature (a 1-D sweep)")
        cases = []
        for i, temp in enumerate(self.temperatures):
            cases.append(self._case_dict(i, float(temp)))
        document: dict[str, Any] = {
            "ecdsim_version": __version__,
            "system": self.system.name,
            "methods": list(self.solutions),
            "cases": cases,
            "warnings": [w.to_dict() for w in self.warnings],
        }
        if self.flight is not None:
            document["ground_test"] = self._ground_test()
        return document

    def _ground_test(self) -> dict[str, Any]:
        """The gravity of the ground test, and flight against test per case and method.

        The prediction itself is the test (as configured, in 1 g); ``flight`` the same
        system in 0 g. ``test_minus_flight`` is None where either stalls.
        """
        gravity = self.system.load.gravity
        assert gravity is not None
        assert self.flight is not None
        travel = float(np.max(self.problem.travel))
        cases = []
        for i, temp in enumerate(self.temperatures):
            by_method: dict[str, Any] = {}
            for name, test in self.solutions.items():
                flight = self.flight.solutions[name]
                t_test = float(np.broadcast_to(test.deployment_time, self.temperatures.shape)[i])
                t_flight = float(
                    np.broadcast_to(flight.deployment_time, self.temperatures.shape)[i]
                )
                both = math.isfinite(t_test) and math.isfinite(t_flight)
                by_method[name] = {
                    "flight_deployment_time_s": t_flight if math.isfinite(t_flight) else None,
                    "test_deployment_time_s": t_test if math.isfinite(t_test) else None,
                    "test_minus_flight_s": t_test - t_flight if both else None,
                    "relative": (t_test - t_flight) / t_flight if both else None,
                }
            cases.append({"temperature_C": float(temp), **by_method})
        return {
            "mass_kg": float(np.max(gravity.mass)),
            "cg_radius_m": float(np.max(gravity.cg_radius)),
            "release_angle_rad": float(np.max(gravity.release_angle)),
            "offload": float(np.max(gravity.offload)),
            "gravity_m_s2": STANDARD_GRAVITY,
            "torque_amplitude_Nm": float(np.max(gravity.amplitude)),
            "torque_at_release_Nm": float(np.max(gravity.torque_at(0.0))),
            "torque_at_latch_Nm": float(np.max(gravity.torque_at(travel))),
            "cases": cases,
        }

    def _case_dict(self, i: int, temperature: float) -> dict[str, Any]:
        e = self.ecd

        def at(array: FloatArray) -> float:
            return float(np.broadcast_to(array, self.temperatures.shape)[i])

        case: dict[str, Any] = {
            "temperature_C": temperature,
            "damping_rate_Nms_per_rad": at(e.ecd_damping_rate),
            "friction_Nm": at(e.ecd_friction),
            "system_friction_Nm": at(self.system_friction),
            "total_friction_Nm": at(self.problem.friction),
            "start_torque_Nm": at(self.problem.torques[0]),
            "end_torque_Nm": at(self.problem.torques[-1]),
            "travel_rad": at(self.problem.travel),
            "components": {
                "damper_damping_rate_Nms_per_rad": at(e.damper_damping_rate),
                "gearbox_damping_rate_Nms_per_rad": at(e.gearbox_damping_rate),
                "high_speed_total_damping_rate_Nms_per_rad": at(e.total_damping_rate),
                "damper_friction_Nm": at(e.damper_friction),
                "lubrication_friction_Nm": at(e.lubrication_friction),
                "gearbox_friction_Nm": at(e.gearbox_friction),
                "high_speed_total_friction_Nm": at(e.total_friction),
                "gear_ratio": at(e.gear_ratio),
                "lost_motion_rad": float(self.system.ecd.gearbox.lost_motion),
            },
        }
        for name, solution in self.solutions.items():
            time = at(solution.deployment_time)
            stalled = bool(np.broadcast_to(solution.stalled, self.temperatures.shape)[i])
            solved = bool(np.broadcast_to(solution.solved_mask, self.temperatures.shape)[i])

            # A case the method cannot solve has no speeds either (not 0: null in JSON).
            speeds = {
                key: at(values) if solved else None
                for key, values in (
                    ("start_speed_rad_s", solution.start_speed),
                    ("end_speed_rad_s", solution.end_speed),
                    ("max_speed_rad_s", solution.max_speed),
                )
            }
            case[name] = {
                "solved": solved,
                "deployment_time_s": time if np.isfinite(time) else None,
                **speeds,
                "stalled": stalled,
                "stall_angle_rad": at(solution.stall_angle) if stalled else None,
            }
            case[name].update(solution.case_fields(i))
        if "paper" in self.solutions and "exact" in self.solutions:
            paper_t = case["paper"]["deployment_time_s"]
            exact_t = case["exact"]["deployment_time_s"]
            if paper_t is None or exact_t is None:
                case["difference"] = {"deployment_time_s": None, "relative": None}
            else:
                case["difference"] = {
                    "deployment_time_s": paper_t - exact_t,
                    "relative": (paper_t - exact_t) / exact_t,
                }
        return case


def build_problem(
    system: DeploymentSystem, ecd: EcdState, temperatures: FloatArray
) -> tuple[QuasiStaticProblem, FloatArray]:
    """The quasi-static problem at the given temperatures, and FS_T [N*m]."""
    load = system.load
    gravity = load.gravity
    spring = load.drive
    if gravity is None and temperatures.size == 1 and type(spring) is LinearSpring:
        packed = _one_case_linear_problem(system, spring, ecd, temperatures)
        if packed is not None:
            return packed
    fs = np.asarray(load.system_friction(temperatures), dtype=float)
    friction = np.asarray(ecd.ecd_friction + fs, dtype=float)
    angles, torques = spring.breakpoints(load.travel, temperatures)
    if gravity is None and temperatures.size == 1:
        one = one_case_problem(
            np.asarray(angles, dtype=float),
            np.asarray(torques, dtype=float),
            friction,
            np.asarray(ecd.ecd_damping_rate, dtype=float),
        )
        if one is not None:
            return one, fs
    problem = QuasiStaticProblem(
        angles=np.asarray(angles, dtype=float),
        torques=np.asarray(torques, dtype=float),
        friction=friction,
        damping_rate=np.asarray(ecd.ecd_damping_rate, dtype=float),
        # A ground test's gravity torque (docs/model.md); None in flight, as before.
        gravity_amplitude=None if gravity is None else gravity.amplitude,
        gravity_angle=None if gravity is None else np.asarray(gravity.release_angle, float),
    )
    return problem, fs


def _one_case_linear_problem(
    system: DeploymentSystem, spring: LinearSpring, ecd: EcdState, temperatures: FloatArray
) -> tuple[QuasiStaticProblem, FloatArray] | None:
    """:func:`build_problem` of one temperature, a linear spring and no gravity, or None.

    The spring's breakpoints (:meth:`LinearSpring.one_case_breakpoints`) and a linear
    FS_T law (:meth:`LinearTemperatureLaw.one_case`) in floats, the total friction
    FECD_T + FS_T added as NumPy adds their arrays (the same bits), all packed with the
    damping into the problem's one array (``solvers.base.packed_problem``); FS_T as the
    law's array of the temperatures' shape. None, for the general path (and NumPy's
    overflow warnings), where a part declines, a value is not finite, or FECD_T or
    BECD_T holds more than one case.
    """
    load = system.load
    temperature = temperatures.item()
    points = spring.one_case_breakpoints(load.travel, temperature)
    law = load.system_friction
    fs = law.one_case(temperature) if type(law) is LinearTemperatureLaw else None
    ecd_friction, damping = ecd.ecd_friction, ecd.ecd_damping_rate
    if points is None or fs is None or ecd_friction.size != 1 or damping.size != 1:
        return None
    if ecd_friction.dtype != np.float64 or damping.dtype != np.float64:
        return None
    friction = ecd_friction.item() + fs
    if not math.isfinite(friction):
        return None
    batch = joint_shape(temperatures.shape, ecd_friction.shape, damping.shape)
    problem = packed_problem(*points, friction, damping.item(), batch)
    # The law's answer has the temperatures' shape (its parameters are floats).
    return problem, np.array(fs, dtype=np.float64).reshape(temperatures.shape)


def predict(
    system: DeploymentSystem,
    temperatures: ArrayLike,
    methods: Sequence[str] = DEFAULT_METHODS,
    dynamics: DynamicParameters | None = None,
) -> Prediction:
    """Predict the deployment at each temperature [degC] by each named method.

    ``dynamics`` (inertia, stiction, end stop, ...) is needed by every method whose solver
    ``needs_dynamics`` (the ``dynamic`` method); when given, every method solves the same
    :class:`~ecdsim.dynamics.DynamicProblem` (the quasi-static methods use its
    quasi-static part). Raises
    :class:`ModelDomainError` where the damping law gives a non-positive damping rate
    (the model has no meaning there) or a dynamic parameter is out of its domain, and
    ``KeyError`` for an unknown method.
    """
    unknown = [m for m in methods if m not in SOLVERS]
    if unknown:
        raise KeyError(f"unknown method(s) {unknown}; known: {sorted(SOLVERS)}")
    temps = np.asarray(temperatures, dtype=float)
    with np.errstate(over="ignore"):  # an overflow is reported by _check_finite
        ecd = system.ecd.at(temps)
    _check_finite(ecd)
    _check_damping_positive(ecd)
    problem, fs = build_problem(system, ecd, temps)
    if dynamics is not None:
        try:
            base = problem
            problem = dynamic_problem(system, ecd, temps, problem, fs, dynamics)
        except DynamicDomainError as exc:
            raise ModelDomainError(exc.key, exc.message) from None
        if base.has_gravity:  # a ground test: the dynamic method integrates gravity too
            problem = replace(
                problem,
                gravity_amplitude=base.gravity_amplitude,
                gravity_angle=base.gravity_angle,
            )
    elif needing := [m for m in methods if SOLVERS[m].needs_dynamics]:
        raise ModelDomainError(
            "load.inertia",
            f"missing; the {needing[0]} method needs the load's moment of inertia about the "
            "ECD input shaft, e.g. inertia = '5 kg*m^2' in [load]",
        )
    solutions = {name: SOLVERS[name].solve(problem) for name in methods}
    prediction = Prediction(
        system=system,
        temperatures=temps,
        ecd=ecd,
        system_friction=fs,
        problem=problem,
        solutions=solutions,
    )
    prediction.warnings.extend(collect_warnings(prediction))
    return prediction


def with_flight(prediction: Prediction, dynamics: DynamicParameters | None = None) -> Prediction:
    """``prediction`` with its flight (0 g) twin when the system has ``[load.gravity]``.

    The configured system is the ground test; the twin is the same system without
    gravity, solved by the same methods at the same temperatures, so that the output can
    show both and their difference (docs/model.md, gravity in ground tests).
    """
    load = prediction.system.load
    if load.gravity is None:
        return prediction
    flight_system = replace(prediction.system, load=replace(load, gravity=None))
    flight = predict(
        flight_system, prediction.temperatures, list(prediction.solutions), dynamics=dynamics
    )
    return replace(prediction, flight=flight)


def _check_finite(ecd: EcdState) -> None:
    # An input large enough to overflow a derived quantity (ratio = 1e200 squares to inf in
    # Eq. 3) would give an infinite result that no output can carry: name the input.
    derived = {
        "BECD_T (Eq. 3)": ecd.ecd_damping_rate,
        "FECD_T (Eq. 4)": ecd.ecd_friction,
    }
    for label, values in derived.items():
        if _all_finite(values):
            continue
        ratio = float(np.max(np.abs(ecd.gear_ratio)))
        gearbox = float(np.max(np.abs(ecd.gearbox_damping_rate)))
        damper = float(np.max(np.abs(ecd.damper_damping_rate)))
        if not np.isfinite(ratio * ratio):
            key = "gearbox.ratio"
        elif label.startswith("FECD"):
            key = "damper.coulomb_friction"
        elif gearbox > damper:
            key = "gearbox.damping_fraction"
        else:
            key = "damper.damping_rate"
        raise ModelDomainError(
            key,
            f"the inputs make {label} overflow to infinity (gear ratio {ratio:.4g}, BD_T "
            f"{damper:.4g} N*m*s/rad, BG {gearbox:.4g} N*m*s/rad); check their magnitudes "
            "and units",
        )


def _all_finite(values: FloatArray) -> bool:
    """``all_true(np.isfinite(values))``; one number tested as a Python float (the same
    answer for inf and NaN), without NumPy's ufunc (issue 13, single cases)."""
    if values.size == 1:
        return math.isfinite(values.item())
    return all_true(np.isfinite(values))


def _check_damping_positive(ecd: EcdState) -> None:
    # The damper's own rate must not go negative, not only the total: a negative BD_T
    # hidden by the gearbox's BG is still a temperature law used beyond its range. Zero is
    # a real case (an undamped coast, a damper removed): the methods that cannot solve it
    # say so per case (DeploymentSolution.solved).
    rate = ecd.ecd_damping_rate
    damper_rate = ecd.damper_damping_rate
    # One test first, the usual answer: min(BD_T, BECD_T) >= 0 holds exactly where both
    # do (np.minimum propagates a NaN, which fails the test as it fails either). One
    # number each (a single deployment): the same test on the floats, NaN failing it too.
    if rate.size == 1 and damper_rate.size == 1:
        if damper_rate.item() >= 0.0 and rate.item() >= 0.0:
            return
    elif all_true(np.minimum(damper_rate, rate) >= 0.0):
        return
    damper = np.broadcast_to(ecd.damper_damping_rate, np.shape(rate))
    bad = ~(damper >= 0.0) | ~(rate >= 0.0)
    if np.any(bad):
        where = np.broadcast_to(ecd.temperature, bad.shape)[bad]
        value = damper[bad]
        raise ModelDomainError(
            "damper.damping_temperature_coefficient",
            f"at {float(where.flat[0]):g} degC the damping law gives a damper damping rate "
            f"BD_T = {float(value.flat[0]):.4g} N*m*s/rad < 0; the linear temperature law "
            "does not reach that far",
        )


def _temperature_at(
    prediction: Prediction, mask: BoolArray, shape: tuple[int, ...] | None = None
) -> list[float]:
    """The distinct temperatures where ``mask`` (broadcast to ``shape`` if given) holds."""
    if not any_true(mask):  # the usual answer, at once (a single case pays every call)
        return []
    if shape is not None:
        mask = np.broadcast_to(mask, shape)
    temps = np.broadcast_to(prediction.temperatures, mask.shape)
    return sorted({float(t) for t in temps[mask]})


def collect_warnings(prediction: Prediction) -> list[ModelWarning]:
    """Every finding for the prediction: stalls, linear range, tables, negative friction."""
    found: list[ModelWarning] = []
    system = prediction.system
    temps = prediction.temperatures
    laws = {
        "damper.lubrication_friction": system.ecd.damper.lubrication_friction,
        "load.system_friction": system.load.system_friction,
    }
    for key, law in laws.items():
        if type(law) is LinearTemperatureLaw:
            continue  # no stated range: never out of range (its out_of_range is all False)
        outside = law.out_of_range(temps)
        for t in _temperature_at(prediction, np.asarray(outside)):
            found.append(
                ModelWarning(
                    "table_extrapolation",
                    f"{key}: {t:g} degC is outside the table ({law.describe()}); "
                    "the value is held at the nearest end point",
                    t,
                )
            )
    negative = {
        "FECD": prediction.ecd.ecd_friction,
        "FS": prediction.system_friction,
    }
    for label, values in negative.items():
        if values.size == 1 and not values.item() < 0.0:
            continue  # one number, not negative (NaN neither): no case to report, at once
        below = np.asarray(values < 0.0)
        for t in _temperature_at(prediction, below, prediction.problem.batch_shape):
            found.append(
                ModelWarning(
                    "negative_friction",
                    f"{label} is negative at {t:g} degC: the friction law is outside the range "
                    "it was fitted over; the result is not physical",
                    t,
                )
            )
    for name, solution in prediction.solutions.items():
        found.extend(_unsolved_warnings(prediction, name, solution))
        found.extend(_stall_warnings(prediction, name, solution))
        found.extend(_linear_range_warnings(prediction, name, solution))
        own = solution.findings()
        if own and temps.size == 1:  # one case: its temperature, without the broadcast
            temperature = temps.item()
            found.extend(ModelWarning(code, message, temperature, name) for code, message, _ in own)
        elif own:
            flat_temps = broadcast(temps, solution.deployment_time.shape).ravel()
            found.extend(
                ModelWarning(code, message, float(flat_temps[i]), name) for code, message, i in own
            )
    return found


def _unsolved_warnings(
    prediction: Prediction, name: str, solution: DeploymentSolution
) -> list[ModelWarning]:
    if solution.solved is None or all_true(np.asarray(solution.solved)):
        return []  # every case solved (the usual answer), at once
    unsolved = ~solution.solved_mask
    return [
        ModelWarning(
            "not_solved",
            f"the {name} method cannot solve the case at {t:g} degC: the ECD's damping rate "
            "BECD_T is 0 (or so small that the speed overflows), so its quasi-static "
            "equation gives an infinite speed; use the dynamic method (give [load] inertia)",
            t,
            name,
        )
        for t in _temperature_at(prediction, unsolved)
    ]


def _friction_at_release(prediction: Prediction, solution: DeploymentSolution) -> FloatArray:
    """The friction the spring must overcome at release [N*m], as ``solution`` models it.

    The quasi-static methods use the kinetic friction FECD_T + FS_T; the dynamic method
    the breakaway (static) friction of what is engaged at release (the ECD only without
    lost motion).
    """
    problem = getattr(solution, "problem", None)
    if not isinstance(problem, DynamicProblem):
        return np.asarray(prediction.problem.friction, dtype=float)
    system = mechanics.static_friction(
        problem.system_friction, problem.system_static_friction_factor
    )
    ecd = mechanics.static_friction(problem.ecd_friction, problem.static_friction_factor)
    return np.asarray(system + np.where(problem.lost_motion > 0.0, 0.0, ecd), dtype=float)


def _stall_warnings(
    prediction: Prediction, name: str, solution: DeploymentSolution
) -> list[ModelWarning]:
    out: list[ModelWarning] = []
    stalled = solution.stalled
    if not any_true(stalled):
        return out
    shape = stalled.shape
    temps = np.broadcast_to(prediction.temperatures, shape)
    problem = prediction.problem
    at_release = problem.torques[0]
    what = "spring torque"
    if problem.has_gravity:  # a ground test: the drive is the spring less gravity
        assert problem.gravity_amplitude is not None
        assert problem.gravity_angle is not None
        at_release = at_release - problem.gravity_amplitude * np.sin(problem.gravity_angle)
        what = "spring torque less gravity"
    drive = np.broadcast_to(at_release, shape)
    friction = np.broadcast_to(_friction_at_release(prediction, solution), shape)
    for t, angle, start, resist in zip(
        temps[stalled],
        solution.stall_angle[stalled],
        drive[stalled],
        friction[stalled],
        strict=True,
    ):
        if float(angle) == 0.0:
            # Say what happened at release rather than "stalls at 0 rad".
            message = (
                f"cannot start: drive torque {float(start):.4g} N*m < friction "
                f"{float(resist):.4g} N*m at {float(t):g} degC (at release)"
            )
        else:
            message = (
                f"stalls at {float(angle):.4g} rad ({np.degrees(float(angle)):.1f} deg) at "
                f"{float(t):g} degC: {what} falls to the friction before the end of travel"
            )
        out.append(ModelWarning("stall", message, float(t), name))
    return out


def _linear_range_warnings(
    prediction: Prediction, name: str, solution: DeploymentSolution
) -> list[ModelWarning]:
    damper = prediction.system.ecd.damper
    if damper.max_linear_speed is None and damper.max_linear_torque is None:
        return []  # no linear-range limits given: nothing to check
    ecd = prediction.ecd
    # A shaft speed that overflows (start_torque = 1e308 N*m) is past any limit: compared as inf.
    with np.errstate(over="ignore"):
        shaft_speed = solution.max_speed * ecd.gear_ratio
        checks: list[tuple[str, float | None, FloatArray, str]] = [
            ("linear_range_speed", damper.max_linear_speed, shaft_speed, "rad/s"),
            (
                "linear_range_torque",
                damper.max_linear_torque,
                damper_torque(ecd.damper_damping_rate, shaft_speed),
                "N*m",
            ),
        ]
    out = []
    for code, limit, value, unit in checks:
        if limit is None:
            continue
        value_b = np.broadcast_to(value, solution.max_speed.shape)
        over = value_b > limit
        temps = np.broadcast_to(prediction.temperatures, over.shape)
        for t, v in zip(temps[over], value_b[over], strict=True):
            what = "speed" if code.endswith("speed") else "eddy-current torque"
            excess = 100.0 * (float(v) / limit - 1.0)
            out.append(
                ModelWarning(
                    code,
                    f"peak damper {what} {float(v):.4g} {unit} at {float(t):g} degC exceeds the "
                    f"linear-range limit {limit:.4g} {unit} by {excess:.1f} %",
                    float(t),
                    name,
                )
            )
    return out
