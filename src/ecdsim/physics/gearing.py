"""A lossy step-up gear: mesh efficiency forward and back-driven (issue 16 item 5).

Source: the Modelica Standard Library's ``Modelica.Mechanics.Rotational.Components.
LossyGear`` (documentation of the component, MSL 3.2/4.0): with gear ratio i and the
mesh efficiency eta_mf, ``-(flange_b.tau) = i * eta_mf * flange_a.tau`` (no bearing
friction), where ``eta_mf = eta_mf1`` when power flows from flange_a (the driving
flange) to flange_b, and the power flowing back is reduced by ``eta_mf2`` (power at a
= eta_mf2 * power from b). The direction of the power flow, not of the motion, decides
the efficiency; at rest the gear is stuck while the torques can be held within both
bounds (Pfeiffer and Glocker, *Multibody Dynamics with Unilateral Contacts*, Wiley 1996,
the friction-mode logic that the component implements; Pelchen, Schweiger and Otter,
"Modeling and simulating the efficiency of gearboxes and of planetary gearboxes",
2nd International Modelica Conference, 2002).

In an ECD deployment flange_a is the slow input shaft (the load) and flange_b the fast
damper shaft; the gear ratio N is fast turns per input turn (the paper's N). With
``tau_out`` the torque the damper side needs at the fast shaft (its damping and
friction, plus its inertia's), the torque the load must apply at the input is

    forward (the load drives the damper):          tau_in = N tau_out / eta_f
    back-driven (the damper side drives the load): tau_in = N tau_out * eta_b

Every function is vectorised; efficiencies are dimensionless in (0, 1].
"""

import numpy as np

from ecdsim._types import ArrayLike, FloatArray, Real, as_float


def refer_damping_through_mesh(
    high_speed_rate: ArrayLike, gear_ratio: ArrayLike, forward_efficiency: ArrayLike
) -> FloatArray:
    """Eq. 3 through a lossy mesh driven forward: ``BECD_T = BT_T * N**2 / eta_f``.

    The load drives the damper in a deployment, so the damping torque N BT_T (N omega)
    that the damper side needs is raised by the mesh loss at the input: the LossyGear
    law ``tau_in = N tau_out / eta_f`` applied to ``tau_out = BT_T N omega``.

    Parameters
    ----------
    high_speed_rate : BT_T, total damping at the high-speed shaft [N*m*s/rad]
    gear_ratio : N, high-speed shaft turns per input shaft turn [-]
    forward_efficiency : eta_f, mesh efficiency with the input driving, in (0, 1] [-]

    >>> round(float(refer_damping_through_mesh(1.638e-4, 380, 0.8)), 4)
    29.5659
    """
    n = as_float(gear_ratio)
    return as_float(as_float(high_speed_rate) * n * n / as_float(forward_efficiency))


def refer_friction_through_mesh(
    high_speed_friction: ArrayLike, gear_ratio: ArrayLike, forward_efficiency: ArrayLike
) -> FloatArray:
    """Eq. 4 through a lossy mesh driven forward: ``FECD_T = FT_T * N / eta_f``.

    Parameters
    ----------
    high_speed_friction : FT_T, total friction at the high-speed shaft [N*m]
    gear_ratio : N, high-speed shaft turns per input shaft turn [-]
    forward_efficiency : eta_f, mesh efficiency with the input driving, in (0, 1] [-]
    """
    return as_float(
        as_float(high_speed_friction) * as_float(gear_ratio) / as_float(forward_efficiency)
    )


def input_torque(
    reflected_torque: ArrayLike,
    speed: ArrayLike,
    forward_efficiency: ArrayLike,
    backward_efficiency: ArrayLike,
) -> FloatArray:
    """Torque the load applies at the input for a damper-side torque, either power flow.

    ``reflected_torque`` is ``N tau_out``, the damper side's torque as an ideal gear would
    pass it to the input. Where it and the input speed have the same sign (or the speed
    is zero: breakaway always drives the damper) the load drives the damper and the
    result is ``N tau_out / eta_f``; where they have opposite signs the damper side's
    inertia drives the load and the result is ``N tau_out * eta_b``. Source: the MSL
    LossyGear mesh law of the module notes, on the paper's reflection through N (Eq. 3-4).

    Parameters
    ----------
    reflected_torque : N tau_out [N*m]
    speed : input shaft speed [rad/s]
    forward_efficiency : eta_f in (0, 1] [-]
    backward_efficiency : eta_b in (0, 1] [-]
    """
    tau = as_float(reflected_torque)
    forward = tau * as_float(speed) >= 0.0
    return as_float(
        np.where(forward, tau / as_float(forward_efficiency), tau * as_float(backward_efficiency))
    )


def mesh_loss_power(
    reflected_torque: ArrayLike,
    speed: ArrayLike,
    forward_efficiency: ArrayLike,
    backward_efficiency: ArrayLike,
) -> FloatArray:
    """Power lost in the mesh, ``tau_in omega - N tau_out omega`` >= 0 [W].

    Forward: ``(1/eta_f - 1) |N tau_out omega|``; back-driven: ``(1 - eta_b) |N tau_out
    omega|`` (the power the damper side delivers, less what reaches the load). Source:
    the power balance of the MSL LossyGear (module notes) with the paper's Eq. 3-4.

    Parameters
    ----------
    reflected_torque : N tau_out [N*m]
    speed : input shaft speed [rad/s]
    forward_efficiency : eta_f in (0, 1] [-]
    backward_efficiency : eta_b in (0, 1] [-]
    """
    w = as_float(speed)
    tau_in = input_torque(reflected_torque, w, forward_efficiency, backward_efficiency)
    return as_float((tau_in - as_float(reflected_torque)) * w)


def power_flow_indicator(
    load_inertia: Real, damper_inertia: Real, damper_torque: Real, load_torque: Real
) -> Real:
    """A quantity with the sign of the mesh torque ``N tau_out`` while the gear turns.

    The load (inertia ``J_L`` at the input) feels ``load_torque`` A (spring, resistance
    and system friction) and the gear; the damper side (inertia ``J_D`` referred to the
    input, ``N**2`` times its own) feels its torque ``D = N tau_d`` (damping and
    friction, as an ideal gear reflects them). Eliminating the common acceleration,

        N tau_out = (J_L D + J_D A) / (J_L + m J_D),   m = 1/eta_f or eta_b > 0,

    so ``J_L D + J_D A`` has the sign of the mesh torque whichever efficiency applies: the
    load drives the damper (forward efficiency) where it has the sign of the speed, the
    damper side drives the load (back-driven) where the signs differ. It is continuous
    in the state, and at its zero both modes give the same acceleration A / J_L (the mesh
    passes no torque), so a switch of the power flow is a plain event. Source: Newton's
    second law for the two inertias coupled by the MSL LossyGear mesh (module notes;
    Pelchen et al. 2002, section 3), with the paper's Eq. 3-4 reflection.

    Parameters
    ----------
    load_inertia : J_L [kg*m^2]
    damper_inertia : J_D, rotor and gear train referred to the input [kg*m^2]
    damper_torque : D, damper-side torque reflected by an ideal gear [N*m]
    load_torque : A, the torque on the load other than the gear's [N*m]
    """
    return load_inertia * damper_torque + damper_inertia * load_torque


def power_flow_mode(indicator: Real, hint: int) -> int:
    """The power flow a lossy gear takes for a segment: +1 forward (the load drives the
    damper), -1 back-driven.

    ``indicator`` has the sign of the mesh torque along the motion
    (:func:`power_flow_indicator`); at its zero, where a power_flow event has just
    switched the flow, both flows are consistent and ``hint`` (the flow switched to; 0
    none) decides. At rest or at an exact zero without a hint the load drives the damper
    (breakaway always does: :func:`input_torque`). Source: the MSL LossyGear's mode
    logic (module notes; Pelchen et al. 2002, section 3).

    Parameters
    ----------
    indicator : the sign of the mesh torque along the motion [N*m, or kg*m^2*N*m]: the
        mesh torque itself, or :func:`power_flow_indicator`
    hint : the flow a power_flow event has just switched to, +1 or -1, or 0 [-]
    """
    if hint != 0:
        return hint
    return 1 if indicator >= 0.0 else -1


def mesh_factor(flow: int, forward_efficiency: Real, backward_efficiency: Real) -> Real:
    """The factor m on the damper side's torque and inertia seen at the input for a
    power flow (:func:`input_torque`): ``1 / eta_f`` forward, ``eta_b`` back-driven.
    Source: the MSL LossyGear mesh law of the module notes on the paper's reflection
    through N (Eq. 3-4).

    Parameters
    ----------
    flow : +1 forward, -1 back-driven [-]
    forward_efficiency : eta_f in (0, 1] [-]
    backward_efficiency : eta_b in (0, 1] [-]
    """
    return 1.0 / forward_efficiency if flow > 0 else backward_efficiency
