"""The ECD and the fluid damper by the dynamic method (``compare-fluid -m dynamic``).

The quasi-static comparison (:func:`ecdsim.sizing.fluid.compare_fluid`) balances each
damper's torque against the net spring torque and treats the deadband as a separate free
phase. The dynamic method integrates both deployments with inertia on the one dynamic
core (:mod:`ecdsim.dynamics.kernel`): the ECD's from the config (its gearbox, lost motion,
stiction and every other effect of ``[dynamics]``-style keys), and the fluid damper's as
the same hinge with its own damper: the power law of :mod:`ecdsim.physics.fluid` at the
load's shaft (``c(T)``, ``n(T)`` at each temperature), its deadband as the lost motion
(the load moves undamped, against the system friction only, until it closes), its own
Coulomb friction, no gear train and no damper inertia (docs/qualification.md section 3).
"""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np

from ecdsim._types import ArrayLike, FloatArray, as_float
from ecdsim.dynamics.damping import PowerLawDamper
from ecdsim.dynamics.method import DynamicSolution
from ecdsim.dynamics.params import DynamicParameters
from ecdsim.dynamics.problem import DynamicProblem
from ecdsim.dynamics.result import EVENT_KINDS, DynamicResult
from ecdsim.model import DeploymentSystem
from ecdsim.sizing.fluid import DeadbandDeployment

# The power law's linear core: below omega_l = LINEAR_CORE * omega_r the fluid is taken
# as Newtonian (docs/qualification.md section 3). The bench data never reach that far
# (a flight damper's tested speeds span a decade or two around omega_r); the core keeps
# the stiff integrator's Jacobian finite at rest, and changes a deployment's time by far
# less than the integrator's tolerance (tests/test_fluid_dynamic.py measures it).
LINEAR_CORE = 1e-6


def fluid_problem(
    base: DynamicProblem,
    coefficient: ArrayLike,
    exponent: ArrayLike,
    reference_speed: float,
    friction: ArrayLike,
    deadband: float,
) -> DynamicProblem:
    """The fluid damper's dynamic problem: ``base`` (the ECD's, for its spring, load,
    system friction and settings) with the fluid damper in the ECD's place.

    Parameters
    ----------
    base : the ECD's dynamic problem at the same temperatures
    coefficient : c(T) of ``T = c omega**n`` [N*m*(s/rad)**n]
    exponent : n(T) [-]
    reference_speed : omega_r, the speed the law was measured about [rad/s] (sets the
        linear core LINEAR_CORE * omega_r and the speed scale of the tolerances)
    friction : the fluid damper's Coulomb friction [N*m] (breakaway equal to it)
    deadband : the fluid damper's free angle at the start [rad]
    """
    c = as_float(coefficient)
    n = as_float(exponent)
    law = PowerLawDamper(c, n, LINEAR_CORE * reference_speed)
    fluid_friction = as_float(friction)
    # The secant rate at omega_r: the kernel's speed scale for its tolerances (never a
    # closed-form segment's damping: those refuse the power law).
    secant = as_float(c * np.power(reference_speed, n - 1.0))
    return replace(
        base,
        friction=as_float(fluid_friction + base.system_friction),
        damping_rate=secant,
        eddy=law,
        ecd_friction=fluid_friction,
        static_friction_factor=np.asarray(1.0),
        damper_inertia=np.asarray(0.0),
        lost_motion=np.asarray(float(deadband)),
        gear_ratio=np.asarray(1.0),
        gearbox_damping_rate=np.asarray(0.0),
        forward_efficiency=np.asarray(1.0),
        backward_efficiency=np.asarray(1.0),
        stribeck_speed=np.asarray(math.inf),
        gear_stiffness=np.asarray(math.inf),
        gear_mesh_damping=np.asarray(0.0),
        heat_capacity=np.asarray(math.inf),
        thermal_resistance=np.asarray(math.inf),
        housing_heat_capacity=np.asarray(math.inf),
        housing_thermal_resistance=np.asarray(math.inf),
        initial_rotor_rise=np.asarray(0.0),
        initial_housing_rise=np.asarray(0.0),
        thermal=False,
        two_node=False,
    )


def parameters_for(dynamics: DynamicParameters | None, inertia: float | None) -> DynamicParameters:
    """The dynamic parameters of the comparison: the config's (``[load] inertia`` and the
    keys read with it), with the fluid comparison's load inertia where one is given.
    Raises ValueError without any load inertia."""
    if dynamics is None:
        if inertia is None:
            raise ValueError(
                "fluid_damper.load_inertia: the dynamic method needs the load's inertia "
                "(load_inertia in [fluid_damper], or inertia in [load])"
            )
        return DynamicParameters(load_inertia=inertia)
    if inertia is not None:
        return replace(dynamics, load_inertia=inertia)
    return dynamics


def engagement_speed(result: DynamicResult) -> FloatArray:
    """The load's speed when the lost motion (deadband) closed, per case [rad/s]: 0
    without one (engaged at release), NaN where it never closed."""
    events = result.events
    speed = np.full(result.size, math.nan)
    engaged = np.ravel(result.engagement_time) == 0.0
    speed[engaged] = 0.0
    rows = events.kind == EVENT_KINDS.index("engage")
    speed[events.case[rows]] = events.speed[rows]
    return as_float(speed.reshape(result.batch_shape))


def solve(problem: DynamicProblem) -> DynamicSolution:
    """The dynamic method's solution of ``problem`` (the registry's solver)."""
    from ecdsim.methods import SOLVERS

    solution = SOLVERS["dynamic"].solve(problem)
    assert isinstance(solution, DynamicSolution)
    return solution


def _side(solution: DynamicSolution, deadband: float) -> DeadbandDeployment:
    """A dynamic deployment as the comparison's side: free time to the engagement,
    damped time from it to the arrival (inf where the load never arrives)."""
    result = solution.result
    total = as_float(np.ravel(result.deployment_time))
    arrived = np.isfinite(total)
    free = as_float(np.ravel(result.engagement_time))
    return DeadbandDeployment(
        deadband=deadband,
        damped_time=as_float(np.where(arrived, total - free, np.inf)),
        free_time=free,
        engage_speed=as_float(np.ravel(engagement_speed(result))),
        total_time=as_float(np.where(arrived, total, np.inf)),
        end_speed=as_float(np.where(arrived, np.ravel(result.arrival_speed), 0.0)),
        stalled=np.asarray(~arrived),
    )


def dynamic_sides(
    system: DeploymentSystem,
    temperatures: FloatArray,
    params: DynamicParameters,
    coefficient: FloatArray,
    exponent: FloatArray,
    reference_speed: float,
    friction: FloatArray,
    deadband: float,
) -> tuple[DeadbandDeployment, DeadbandDeployment]:
    """The ECD's and the fluid damper's deployments by the dynamic method at the
    temperatures [degC] (1-D): the ECD as the config has it, the fluid damper on the same
    hinge (:func:`fluid_problem`). Raises :class:`~ecdsim.deployment.ModelDomainError`
    where a dynamic parameter leaves its domain."""
    from ecdsim.deployment import predict

    run = predict(system, temperatures, ("dynamic",), dynamics=params)
    ecd = run.solutions["dynamic"]
    assert isinstance(ecd, DynamicSolution)
    assert isinstance(run.problem, DynamicProblem)
    fluid = solve(
        fluid_problem(run.problem, coefficient, exponent, reference_speed, friction, deadband)
    )
    return _side(ecd, system.ecd.gearbox.lost_motion), _side(fluid, deadband)
