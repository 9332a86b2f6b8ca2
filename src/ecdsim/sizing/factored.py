"""The factor arithmetic of every torque margin: one implementation (docs/qualification.md).

A torque margin sets an available (driving) torque against resistive torques, each
multiplied by the uncertainty factor of its kind::

    margin       = available / sum_i(f_i * T_i) - 1
    torque_ratio = available / sum_i(T_i)

The first is the margin of ECSS-E-ST-33-01C's motorisation-ratio form and of a flight
program's torque budget (kinds ``known``/``unknown``, or the ECSS kinds); the second is
the same ratio with every factor 1, the argument a program weighs when a margin is
negative but the unfactored torques are still overcome. The ECSS torque margin of
:mod:`ecdsim.sizing.margin` (docs/sizing.md section 5) and the torque budget of
:mod:`ecdsim.sizing.budget` both compute through these functions.
"""

from __future__ import annotations

from collections.abc import Iterable

import numpy as np

from ecdsim._types import ArrayLike, FloatArray, as_float

# Below this relative size a margin is float rounding of an exact zero: with damping at the
# deployment's own speed and unit factors, drive and resistance are equal by quasi-static
# equilibrium, and their quotient differs from 1 only in the last bits.
ROUNDING = 1e-12


def factored_sum(terms: Iterable[tuple[float, ArrayLike]]) -> FloatArray:
    """``sum_i(f_i * T_i)`` over (factor [-], torque [N*m]) pairs, arrays broadcast [N*m].

    >>> float(factored_sum([(1.5, 6.5), (3.0, 5.41)]))
    25.98
    """
    total = as_float(0.0)
    for factor, torque in terms:
        total = as_float(total + float(factor) * as_float(torque))
    return total


def margin_over(available: ArrayLike, resisting: ArrayLike) -> FloatArray:
    """``available / resisting - 1`` with the edge cases of a budget [-].

    +inf where nothing resists (``resisting`` = 0) and the available torque is positive,
    -1 where both are zero; a result within :data:`ROUNDING` of 0 is 0. Used both for the
    margin (``resisting`` factored) and, plus one, the torque ratio (unfactored).

    Parameters
    ----------
    available : the available (driving) torque [N*m]
    resisting : the (factored or unfactored) sum of the resistive torques [N*m]

    >>> round(float(margin_over(44.0, 25.98)), 4)
    0.6936
    """
    total, t = np.broadcast_arrays(as_float(resisting), as_float(available))
    positive = total > 0.0
    ratio = t / np.where(positive, total, 1.0)
    margin = np.where(positive, ratio - 1.0, np.where(t > 0.0, np.inf, -1.0))
    return as_float(np.where(np.abs(margin) < ROUNDING, 0.0, margin))


def torque_ratio(available: ArrayLike, total: ArrayLike) -> FloatArray:
    """``available / sum_i(T_i)``, the unfactored torque ratio [-] (+inf where nothing
    resists and the available torque is positive).

    >>> round(float(torque_ratio(44.0, 11.91)), 4)
    3.6944
    """
    return as_float(margin_over(available, total) + 1.0)
