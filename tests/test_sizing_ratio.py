"""Exact gear-ratio intervals: each end verified by forward simulation just inside and just
outside, and against roots of the paper's equations solved by hand in this file."""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.optimize import brentq

from ecdsim.deployment import ModelDomainError, predict
from ecdsim.model import DeploymentSystem, Ecd, Gearbox
from ecdsim.sizing.catalogue import load_catalogue
from ecdsim.sizing.margin import MarginSettings
from ecdsim.sizing.ratio import Interval, RatioIntervals, _intersect, ratio_intervals
from ecdsim.sizing.requirements import Requirements
from tests.conftest import ROOT, paper_system

TEMPS = (-40.0, 25.0, 100.0)
REQUIREMENTS = Requirements(
    TEMPS,
    min_deployment_time=10.0,
    max_deployment_time=60.0,
    max_end_speed=0.1,
    max_input_torque=4.0,
    ratio_range=(10.0, 5000.0),
)
STEP = 1e-6  # relative step just inside / just outside an interval end


def cc16() -> tuple[RatioIntervals, Requirements]:
    catalogue = load_catalogue(ROOT / "examples" / "catalogue.toml")
    damper = catalogue.damper("CDA Cc-16 damper")
    gearbox = catalogue.gearbox("CDA Cc-16 gearbox")
    return ratio_intervals(damper, gearbox, paper_system().load, REQUIREMENTS), REQUIREMENTS


def forward_meets(ratio: float, r: Requirements) -> bool:
    """Forward simulation at one ratio, each requirement compared directly (no margins)."""
    paper = paper_system()
    gearbox = Gearbox(ratio=ratio, coulomb_friction=4.5e-4, damping_fraction=0.26)
    system = DeploymentSystem(Ecd(paper.ecd.damper, gearbox), paper.load)
    p = predict(system, r.temperatures, ("exact",))
    s = p.solutions["exact"]
    t = s.deployment_time
    torque = p.ecd.ecd_friction + p.ecd.ecd_damping_rate * s.max_speed
    ok = not np.any(s.stalled) if r.no_stall else True
    if r.min_deployment_time is not None:
        ok &= bool(np.all(t >= r.min_deployment_time))
    if r.max_deployment_time is not None:
        ok &= bool(np.all(t <= r.max_deployment_time))
    if r.max_end_speed is not None:
        ok &= bool(np.all(s.end_speed <= r.max_end_speed))
    if r.max_input_torque is not None:
        ok &= bool(np.all(torque <= r.max_input_torque))
    return bool(ok)


def test_interval_ends_verified_by_forward_simulation() -> None:
    found, r = cc16()
    assert len(found.intervals) == 1
    ends = 0
    for interval in found.intervals:
        for end, sign, reason in (
            (interval.low, +1.0, interval.low_limited_by),
            (interval.high, -1.0, interval.high_limited_by),
        ):
            if reason == "scan range":
                continue
            ends += 1
            assert forward_meets(end * (1.0 + sign * STEP), r), (end, reason)
            assert not forward_meets(end * (1.0 - sign * STEP), r), (end, reason)
    assert ends == 2
    assert found.catalogue_ratios == ((380.0, True),)  # the paper's 380:1 meets them


# The paper's Eq. 1-4 with N free, typed here from the paper's constants.
BD, FD, FG = 1.3e-4, 7.9e-4, 4.5e-4


def bt(t: float) -> float:
    return BD * (1.0 - 0.004 * (t - 25.0)) + 0.26 * BD


def ft(t: float) -> float:
    return FD + (-2.12e-6 * t + 2.2e-4) + FG


def fs(t: float) -> float:
    return -0.0044 * t + 0.58


def hand_time(n: float, t: float) -> float:
    """t = (B/k) ln(a / (a - k L)), the exact solution of B phi' = Ts - k phi - F."""
    b = bt(t) * n * n
    a = 3.73 - ft(t) * n - fs(t)
    k = (3.73 - 1.58) / 1.57
    return b / k * math.log(a / (a - k * 1.57))


def test_interval_ends_equal_hand_roots_of_the_papers_equations() -> None:
    found, _ = cc16()

    # t(N, T) grows from ~0 at small N to +inf at the stall ratio (Te - FS)/FT.
    def root(target: float, t: float) -> float:
        stall = (1.58 - fs(t)) / ft(t)
        return float(brentq(lambda n: hand_time(n, t) - target, 10.0, stall * (1 - 1e-9)))

    # t <= 60 s must hold at every T: N below the smallest root of t(N, T) = 60.
    high = min(root(60.0, t) for t in TEMPS)
    # t >= 10 s at every T: N above the largest root of t(N, T) = 10.
    low = max(root(10.0, t) for t in TEMPS)
    (interval,) = found.intervals
    # Both root finders converge to ~1e-12 relative on slopes of order 1 s per unit N.
    assert interval.high == pytest.approx(high, rel=1e-9)
    assert interval.low == pytest.approx(low, rel=1e-9)
    assert (interval.low_limited_by, interval.high_limited_by) == (
        "min_deployment_time",
        "max_deployment_time",
    )
    # Stall: Te - FS - FT N = 0 -> N = (Te - FS)/FT, smallest over T (the cold end).
    stall = min((1.58 - fs(t)) / ft(t) for t in TEMPS)
    (no_stall,) = found.by_check["no_stall"]
    assert no_stall.high == pytest.approx(stall, rel=1e-9)
    # End speed (Te - F)/B = 0.1: 0.1 BT N^2 + FT N - (Te - FS) = 0, largest root over T.
    speed = max(
        (-ft(t) + math.sqrt(ft(t) ** 2 + 4 * 0.1 * bt(t) * (1.58 - fs(t)))) / (2 * 0.1 * bt(t))
        for t in TEMPS
    )
    (end_speed,) = found.by_check["max_end_speed"]
    assert end_speed.low == pytest.approx(speed, rel=1e-9)


def test_flat_torque_margin_boundary_is_the_stall() -> None:
    # Damping at the deployment speed, unit factors: the margin is exactly 0 wherever the
    # mechanism moves, negative past the stall; its boundary is the stall root.
    catalogue = load_catalogue(ROOT / "examples" / "catalogue.toml")
    r = Requirements(TEMPS, min_torque_margin=0.0, margin=MarginSettings(), ratio_range=(10, 5000))
    found = ratio_intervals(
        catalogue.damper("CDA Cc-16 damper"),
        catalogue.gearbox("CDA Cc-16 gearbox"),
        paper_system().load,
        r,
    )
    stall = min((1.58 - fs(t)) / ft(t) for t in TEMPS)
    (margin,) = found.by_check["min_torque_margin"]
    assert margin.low == 10.0
    assert margin.high == pytest.approx(stall, rel=1e-9)
    assert forward_meets(margin.high * (1 - STEP), Requirements(TEMPS))
    assert not forward_meets(margin.high * (1 + STEP), Requirements(TEMPS))


def test_intersection_of_interval_lists() -> None:
    a = [Interval(1.0, 5.0, "x", "x"), Interval(8.0, 12.0, "x", "x")]
    b = [Interval(3.0, 10.0, "y", "y")]
    assert _intersect(a, b) == [Interval(3.0, 5.0, "y", "x"), Interval(8.0, 10.0, "x", "y")]
    assert _intersect(a, [Interval(6.0, 7.0, "z", "z")]) == []


def test_damping_law_out_of_range_is_a_domain_error() -> None:
    catalogue = load_catalogue(ROOT / "examples" / "catalogue.toml")
    # BT_T = BD (1 - 0.004 * 375) + 0.26 BD = -0.24 BD < 0 at 400 degC.
    r = Requirements((25.0, 400.0), ratio_range=(10, 5000))
    with pytest.raises(ModelDomainError, match="damping_temperature_coefficient"):
        ratio_intervals(
            catalogue.damper("CDA Cc-16 damper"),
            catalogue.gearbox("CDA Cc-16 gearbox"),
            paper_system().load,
            r,
        )
