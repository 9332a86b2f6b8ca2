"""A whole wing: a planar chain of panels with a spring, an ECD and a latch at every hinge.

:mod:`ecdsim.wing.model` holds the wing's parameters (:class:`Wing`, :class:`Panel`,
:class:`Hinge`, :class:`HingeEcd`, :class:`Latch`, :class:`Cable`,
:class:`GroundTest`); :mod:`ecdsim.wing.result` what a deployment of it returns
(:class:`WingResult`). The wing's solver, on the dynamic core, is still to come
(docs/wing.md).
"""

from ecdsim.wing.model import (
    Cable,
    GroundTest,
    Hinge,
    HingeEcd,
    HingeState,
    Latch,
    Panel,
    Wing,
    WingState,
)
from ecdsim.wing.result import LatchEvent, WingCase, WingEnergy, WingEvent, WingResult

__all__ = [
    "Cable",
    "GroundTest",
    "Hinge",
    "HingeEcd",
    "HingeState",
    "Latch",
    "LatchEvent",
    "Panel",
    "Wing",
    "WingCase",
    "WingEnergy",
    "WingEvent",
    "WingResult",
    "WingState",
]
