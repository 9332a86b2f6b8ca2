"""What the compliant backlash (two degrees of freedom) takes: the limits of its mesh.

The checks :func:`ecdsim.dynamics.problem.dynamic_problem` runs on a compliant gear mesh
(issue 23 item 8: an accepted mesh is solved, one it cannot follow is refused in one
line naming the key): the effects it does not model yet, and the mesh's two-inertia mode
against the limits below.
"""

from __future__ import annotations

import numpy as np

from ecdsim._types import FloatArray
from ecdsim.dynamics.params import DynamicParameters


class DynamicDomainError(ValueError):
    """A dynamic parameter outside its domain; ``key`` names the config field."""

    def __init__(self, key: str, message: str) -> None:
        super().__init__(f"{key}: {message}")
        self.key = key
        self.message = message


# The compliant mesh's two-inertia mode above this [rad/s] (a period under 60 ns), or its
# damping rate above it [1/s], is refused: every contact would be a swarm of events and
# steps, and the rigid model is its limit (docs/dynamics.md, the error falls as 1/c).
MAX_MESH_FREQUENCY = 1e7
# A fast mode (above MESH_RING_FREQUENCY [rad/s]) that the mesh's damping and the damper's
# damp little rings for many periods after each contact, through thousands of bounces and
# a ring-down followed step by step: beyond MAX_MESH_RING radians of the mode per e-fold
# of its decay it is refused (measured on the dynamic example with a 0.25 deg lost motion
# and an undamped mesh: c = 1e10 N*m/rad, 1,440 rad per e-fold, solves in about a second;
# c = 2.8e10, 2,420, runs out of steps in the ring-down; docs/dynamics.md).
MESH_RING_FREQUENCY = 1e5
MAX_MESH_RING = 2000.0


def _check_compliant(
    params: DynamicParameters,
    damper_inertia: float | FloatArray,
    damper_damping: FloatArray,
    lossy: bool,
    gravity: bool,
) -> None:
    """What the compliant backlash (two degrees of freedom) does not model yet."""
    for absent, what in (
        (
            lossy,
            "[gearbox] efficiency (the lossy gear's power-flow switch is modelled for "
            "the rigid mesh only)",
        ),
        (
            gravity,
            "[load.gravity] (a ground test's gravity torque is modelled for the rigid mesh only)",
        ),
    ):
        if absent:
            raise DynamicDomainError("gearbox.stiffness", f"cannot be combined with {what} yet")
    if params.thermal is not None:
        raise DynamicDomainError(
            "gearbox.stiffness",
            "cannot be combined with [damper.thermal] yet (self-heating is modelled for "
            "the rigid mesh only)",
        )
    if params.stribeck_speed is not None:
        raise DynamicDomainError(
            "gearbox.stiffness",
            "cannot be combined with [damper] stribeck_speed yet (Stribeck friction is "
            "modelled for the rigid mesh only)",
        )
    if np.any(np.asarray(damper_inertia) <= 0.0):
        raise DynamicDomainError(
            "gearbox.stiffness",
            "needs a damper-side inertia: give [damper] rotor_inertia or [gearbox] inertia "
            "> 0 kg*m^2 (a massless damper side behind a compliant mesh has no dynamics)",
        )
    _check_mesh_mode(params, np.asarray(damper_inertia, dtype=float), damper_damping)


def _check_mesh_mode(
    params: DynamicParameters, damper_inertia: FloatArray, damper_damping: FloatArray
) -> None:
    """The compliant mesh's two-inertia mode: its frequency ``sqrt(c (1/J_L + 1/J_D))``,
    the mesh's damping rate ``d (1/J_L + 1/J_D)`` and the mode's decay rate ``(d (1/J_L +
    1/J_D) + BECD / J_D) / 2`` against the limits above."""
    per_inertia = 1.0 / np.asarray(params.load_inertia, dtype=float) + 1.0 / damper_inertia
    frequency = np.sqrt(np.asarray(params.gear_stiffness, dtype=float) * per_inertia)
    damping = 0.0 if params.gear_mesh_damping is None else params.gear_mesh_damping
    rate = np.asarray(damping, dtype=float) * per_inertia
    if np.any(rate > MAX_MESH_FREQUENCY):
        raise DynamicDomainError(
            "gearbox.mesh_damping",
            f"the mesh's damping rate d (1/J_L + 1/J_D) is {float(np.max(rate)):.3g} 1/s, "
            f"above {MAX_MESH_FREQUENCY:.0e} 1/s: a mesh that damped locks the flanks "
            "together, rigid for this model (omit stiffness for the rigid mesh)",
        )
    if np.any(frequency > MAX_MESH_FREQUENCY):
        raise DynamicDomainError(
            "gearbox.stiffness",
            f"the mesh's natural frequency sqrt(c (1/J_L + 1/J_D)) is "
            f"{float(np.max(frequency)):.3g} rad/s, above {MAX_MESH_FREQUENCY:.0e} rad/s: "
            "a mesh that stiff is rigid for this model (omit the key for the rigid mesh, "
            "its limit)",
        )
    decay = 0.5 * (rate + np.asarray(damper_damping, dtype=float) / damper_inertia)
    with np.errstate(divide="ignore"):
        ring = np.where(frequency > MESH_RING_FREQUENCY, frequency / decay, 0.0)
    if np.any(ring > MAX_MESH_RING):
        worst = int(np.argmax(ring))
        w = float(np.broadcast_to(frequency, ring.shape).ravel()[worst])
        sigma = float(np.broadcast_to(decay, ring.shape).ravel()[worst])
        raise DynamicDomainError(
            "gearbox.stiffness",
            f"the mesh's mode (sqrt(c (1/J_L + 1/J_D)) = {w:.3g} rad/s) decays at "
            f"{sigma:.3g} 1/s through the mesh's and the damper's damping: it would ring "
            f"{w / sigma:.3g} rad per e-fold, above the {MAX_MESH_RING:.0f} this model "
            "follows (give gearbox.mesh_damping, a smaller stiffness, or omit stiffness "
            "for the rigid mesh, its limit)",
        )
