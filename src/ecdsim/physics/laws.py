"""Temperature laws for friction-like terms: the paper's linear law and a measured table.

Used for the lubrication friction FL_T (paper section 2.3) and the system friction FS_T
(paper section 5), both printed in the paper as ``slope * T + value_at_0C`` with T in degC.
"""

from collections.abc import Sequence

import numpy as np

from ecdsim._types import ArrayLike, BoolArray, FloatArray, Real, as_float

# Temperatures within this band of a table end count as inside the table [K].
_RANGE_TOLERANCE_K = 1e-9


def linear_in_temperature(temperature: ArrayLike, slope: ArrayLike, at_0c: ArrayLike) -> FloatArray:
    """A quantity linear in temperature: ``slope * T + at_0C`` (the paper's FL_T and FS_T).

    Parameters
    ----------
    temperature : T [degC]
    slope : change per kelvin [unit of the quantity / K]
    at_0c : value at 0 degC [unit of the quantity]

    >>> round(float(linear_in_temperature(25.0, -0.0044, 0.58)), 6)  # FS_25, paper section 6
    0.47
    """
    return as_float(linear_law(as_float(temperature), as_float(slope), as_float(at_0c)))


def linear_law(temperature: Real, slope: Real, at_0c: Real) -> Real:
    """``slope T + at_0C`` of floats or arrays: the paper's FL_T and FS_T (sections 2.3
    and 5; :func:`linear_in_temperature`'s formula, in the subset the damper FMU
    translates to C: :mod:`ecdsim.fmu.ctranslate`).

    Parameters
    ----------
    temperature : T [degC]
    slope : change per kelvin [unit of the quantity / K]
    at_0c : value at 0 degC [unit of the quantity]

    >>> round(linear_law(25.0, -0.0044, 0.58), 12)
    0.47
    """
    return slope * temperature + at_0c


def table_in_temperature(
    temperature: float, temperatures: Sequence[float], values: Sequence[float], count: int
) -> float:
    """:func:`interpolate_table` at one temperature, in plain floats (the damper FMU's
    measured FL_T of paper section 2.3, translated to C by :mod:`ecdsim.fmu.ctranslate`):
    piecewise-linear, held at its end values (NumPy's ``interp``; tests/test_fmu.py holds
    the two equal).

    Parameters
    ----------
    temperature : T [degC]
    temperatures : strictly increasing table temperatures [degC]
    values : the quantity at those temperatures [unit of the quantity]
    count : number of table points, >= 1 [-]

    >>> table_in_temperature(10.0, [0.0, 20.0], [1.0, 3.0], 2)
    2.0
    """
    if temperature <= temperatures[0]:
        return values[0]
    last = count - 1
    if temperature >= temperatures[last]:
        return values[last]
    for i in range(1, count):
        if temperature < temperatures[i]:
            below = i - 1
            slope = (values[i] - values[below]) / (temperatures[i] - temperatures[below])
            return slope * (temperature - temperatures[below]) + values[below]
    return values[last]


def interpolate_table(
    temperature: ArrayLike, table_temperatures: ArrayLike, table_values: ArrayLike
) -> FloatArray:
    """Piecewise-linear interpolation in a (T, value) table; held at the end values outside.

    The measured alternative to the paper's linear FL_T and FS_T (sections 2.3 and 5),
    for lubricants whose friction is not linear in temperature.

    Holding the end value (rather than extrapolating the end slope) keeps a friction from
    turning negative; callers flag the out-of-range points with :func:`outside_table`.

    Parameters
    ----------
    temperature : T [degC]
    table_temperatures : strictly increasing table temperatures [degC]
    table_values : values at the table temperatures [unit of the quantity]

    >>> float(interpolate_table(10.0, [0.0, 20.0], [1.0, 3.0]))
    2.0
    """
    t = as_float(temperature)
    return np.asarray(
        np.interp(t, as_float(table_temperatures), as_float(table_values)),
        dtype=float,
    )


def outside_table(temperature: ArrayLike, table_temperatures: ArrayLike) -> BoolArray:
    """True where T lies outside the table's range (paper section 2.3: no silent extrapolation).

    Parameters
    ----------
    temperature : T [degC]
    table_temperatures : strictly increasing table temperatures [degC]
    """
    t = as_float(temperature)
    grid = as_float(table_temperatures)
    # A table written in degF or K converts to degC with rounding (-40 degF becomes
    # -39.99999999999997 degC); a nanokelvin band keeps such end points inside.
    band = _RANGE_TOLERANCE_K
    return np.asarray((t < grid[0] - band) | (t > grid[-1] + band))
