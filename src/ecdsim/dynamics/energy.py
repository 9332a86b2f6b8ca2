"""The dynamic method's energy account: where each case's energy went [J].

:class:`EnergyBalance` is the account the dynamic kernel keeps term by term (one term per
effect: the spring's work, gravity's, the resistive table's, each dissipation and the
energies left at the end) and its relative closing error, which the result reports.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, fields
from typing import Any

import numpy as np

from ecdsim._types import FloatArray, all_true


@dataclass(frozen=True)
class EnergyBalance:
    """Where the energy went, per case [J]; every array has the batch shape.

    ``spring_work + initial_kinetic_energy = damper_dissipation + friction_dissipation +
    engagement_loss + impact_loss + final_kinetic_energy``. Each term is computed on its
    own (spring work from the angles, friction from the path length, damper dissipation
    from the integral of the damping power, kinetic energies from the speeds), so the
    balance is a check, not an identity.

    Attributes
    ----------
    spring_work : work done by the spring [J]
    initial_kinetic_energy : kinetic energy at release [J]
    damper_dissipation : energy dissipated by the ECD's damping (eddy currents and gearbox
        damping) [J]; with a Stribeck speed it also holds the dissipation of the friction
        above Coulomb, ``(F_brk - F_C) exp(-(w/w_St)^2)``, integrated with the damping
        power in the one dissipation state (:mod:`ecdsim.dynamics.kernel.hinge`), and so
        does a registered effect's, ``-T omega`` (a bearing drag: kernel/effects.py)
    friction_dissipation : energy dissipated by Coulomb friction (FECD and FS), the
        kinetic value times the path length [J]
    engagement_loss : kinetic energy lost when the lost motion closed [J]
    impact_loss : kinetic energy lost in impacts on the stops (rebounds, settling) [J]
    final_kinetic_energy : kinetic energy at the end of the run (absorbed by the latch
        when the run ends latched) [J]
    gear_loss : energy lost in a lossy gear's mesh, forward and back-driven [J] (0 for an
        ideal gear; issue 16 item 5)
    gravity_work : work done against a ground test's gravity, the rise of the CG's
        potential energy ``W (cos(theta_0 + phi_0) - cos(theta_0 + phi_end))`` [J]
        (gravity is conservative: start and end angles suffice); None without gravity
    mesh_dissipation : compliant backlash only: energy dissipated in the gear mesh (its
        damping, and the stored energy lost when the flanks part faster than the mesh
        relaxes) [J]; None for a rigid mesh
    elastic_energy : compliant backlash only: energy stored in the mesh at the end [J]
    resistive_work : work done against a ``[load] resistive_table`` (harness, blanket)
        [J]; spring_work is then the spring's own work, the drive's; None without a table
        (issue 23 item 8)
    """

    spring_work: FloatArray
    initial_kinetic_energy: FloatArray
    damper_dissipation: FloatArray
    friction_dissipation: FloatArray
    engagement_loss: FloatArray
    impact_loss: FloatArray
    final_kinetic_energy: FloatArray
    gear_loss: FloatArray
    gravity_work: FloatArray | None = None
    # Compliant backlash only (None otherwise, so the rigid account is unchanged).
    mesh_dissipation: FloatArray | None = None
    elastic_energy: FloatArray | None = None
    resistive_work: FloatArray | None = None

    def reshaped(self, shape: tuple[int, ...]) -> EnergyBalance:
        """The same balance with arrays of the given shape."""
        values: dict[str, Any] = {
            f.name: None
            if getattr(self, f.name) is None
            else np.asarray(getattr(self, f.name)).reshape(shape)
            for f in fields(self)
        }
        return EnergyBalance(**values)

    def _totals(self, one: bool) -> tuple[Any, Any]:
        """Supplied (spring work plus initial kinetic energy, less the work against gravity
        and a resistive table) and accounted (dissipations, losses, final energies), each
        summed in one order: of arrays, or of one case's floats (``one``)."""

        def term(name: str) -> Any:
            value = getattr(self, name)
            return 0.0 if value is None else value.item() if one else value

        supplied = term("spring_work") + term("initial_kinetic_energy")
        supplied = supplied - term("gravity_work") - term("resistive_work")
        accounted = term("damper_dissipation")
        for name in _ACCOUNTED:
            accounted = accounted + term(name)
        return supplied, accounted

    @property
    def supplied(self) -> FloatArray:
        """Spring work plus initial kinetic energy, less the work against gravity and
        against a resistive table [J]."""
        return np.asarray(self._totals(False)[0])

    @property
    def accounted(self) -> FloatArray:
        """Dissipations, losses and final kinetic energy [J]."""
        return np.asarray(self._totals(False)[1])

    @property
    def error(self) -> FloatArray:
        """Relative imbalance ``(supplied - accounted) / max(|supplied|, |accounted|)``; 0
        where no energy moved.

        One case (every term of one element) is summed in Python floats, the same sums
        in the same order (the same bits) without some twenty NumPy calls (issue 13);
        a sum that is not finite takes the arrays' path (NumPy's NaN and warnings).
        """
        shape = self.spring_work.shape
        if math.prod(shape) == 1 and all(
            getattr(self, name) is None or getattr(self, name).shape == shape for name in _TERMS
        ):
            supplied, accounted = self._totals(True)
            if math.isfinite(supplied) and math.isfinite(accounted):
                scale = max(abs(supplied), abs(accounted))
                error = (supplied - accounted) / scale if scale > 0.0 else 0.0
                return np.array(error, dtype=np.float64).reshape(shape)
        supplied, accounted = self._totals(False)
        scale = np.maximum(np.abs(supplied), np.abs(accounted))
        moved = scale > 0.0
        if all_true(moved):  # energy moved in every case (the usual answer): no guard
            return np.asarray((supplied - accounted) / scale)
        return np.where(moved, (supplied - accounted) / np.where(moved, scale, 1.0), 0.0)


# The terms accounted after the damper's dissipation, in their order of summation.
_ACCOUNTED = (
    "friction_dissipation",
    "engagement_loss",
    "impact_loss",
    "final_kinetic_energy",
    "gear_loss",
    "mesh_dissipation",
    "elastic_energy",
)
# The fields of EnergyBalance, every one a term of the balance (looked up once).
_TERMS = tuple(f.name for f in fields(EnergyBalance))
