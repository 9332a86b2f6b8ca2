"""How often a Monte Carlo study misses each requirement (docs/qualification.md).

For each requirement of the config's ``[requirements]`` that a sample's outputs decide,
the count of samples that miss it, that probability, its exact two-sided 95 % interval
and its one-sided 95 % upper bound (Clopper-Pearson, :mod:`ecdsim.characterize.reliability`),
and the same for missing any of them (one minus the reliability against the whole
specification). What each requirement's miss is:

=====================  ==========================================================
requirement            a sample misses it where
=====================  ==========================================================
min_deployment_time    it arrives faster than t_min (a stall is not "too fast")
max_deployment_time    it arrives slower than t_max, or stalls (t = +inf)
max_end_speed          its speed at the latch exceeds v_max (a stall arrives at 0)
no_stall               it stalls (only with no_stall = true)
min_torque_margin      its smallest torque margin over the travel is below m_min
=====================  ==========================================================

The ECD input torque and the catalogue limits are not sampled (docs/montecarlo.md).
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

import numpy as np

from ecdsim._types import BoolArray, FloatArray
from ecdsim.characterize.reliability import miss_probability

if TYPE_CHECKING:
    from ecdsim.sizing.requirements import Requirements


def miss_flags(
    requirements: Requirements,
    times: FloatArray,
    stalled: BoolArray,
    end_speeds: FloatArray,
    margins: FloatArray | None,
) -> dict[str, tuple[str, BoolArray]]:
    """(label, True where a sample misses it) for each requirement the outputs decide.

    Parameters
    ----------
    requirements : the config's requirements (SI)
    times : deployment time of each sample [s], +inf where stalled
    stalled : True where the sample stalls
    end_speeds : speed at the latch [rad/s]
    margins : smallest torque margin over the travel [-], None if not computed
    """
    r = requirements
    t = np.asarray(times, dtype=float)
    flags: dict[str, tuple[str, BoolArray]] = {}
    if r.min_deployment_time is not None:
        flags["min_deployment_time"] = (
            f"deployment time >= {r.min_deployment_time:g} s",
            np.isfinite(t) & (t < r.min_deployment_time),
        )
    if r.max_deployment_time is not None:
        flags["max_deployment_time"] = (
            f"deployment time <= {r.max_deployment_time:g} s",
            ~(t <= r.max_deployment_time),
        )
    if r.max_end_speed is not None:
        speed = np.asarray(end_speeds, dtype=float)
        flags["max_end_speed"] = (
            f"end speed <= {r.max_end_speed:g} rad/s",
            ~np.asarray(stalled, dtype=bool) & ~(speed <= r.max_end_speed),
        )
    if r.no_stall:
        flags["no_stall"] = ("no stall", np.asarray(stalled, dtype=bool))
    if r.min_torque_margin is not None and margins is not None:
        flags["min_torque_margin"] = (
            f"torque margin >= {r.min_torque_margin:g}",
            ~(np.asarray(margins, dtype=float) >= r.min_torque_margin),
        )
    return flags


def requirement_misses(
    requirements: Requirements,
    times: FloatArray,
    stalled: BoolArray,
    end_speeds: FloatArray,
    margins: FloatArray | None,
) -> dict[str, Any]:
    """The summary's ``requirements`` block of one temperature (module docstring)."""
    flags = miss_flags(requirements, times, stalled, end_speeds, margins)
    block: dict[str, Any] = {}
    for name, (label, missed) in flags.items():
        block[name] = {"label": label, **miss_probability(missed).to_dict()}
    if flags:
        every = np.zeros(np.shape(times), dtype=bool)
        for _, missed in flags.values():
            every |= missed
        block["any"] = {"label": "any requirement", **miss_probability(every).to_dict()}
    return block
