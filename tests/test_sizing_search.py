"""Catalogue search: one vectorised pass that agrees with the paper by hand and with a
separate scalar prediction of every candidate; ranking order; invalid candidates."""

from __future__ import annotations

import json

import numpy as np
import pytest

from ecdsim.deployment import predict
from ecdsim.model import DeploymentSystem
from ecdsim.sizing.catalogue import load_catalogue, parse_toml_catalogue
from ecdsim.sizing.requirements import Requirements
from ecdsim.sizing.search import (
    Candidate,
    CandidateResult,
    catalogue_candidates,
    deployment_time_curves,
    rank_key,
    search,
)
from tests import hand
from tests.conftest import ROOT, paper_system

PAPER_TEMPS = (-40.0, 25.0, 100.0)


def test_cc16_candidate_matches_the_paper_by_hand() -> None:
    catalogue = load_catalogue(ROOT / "examples" / "catalogue.toml")
    requirements = Requirements(PAPER_TEMPS, max_deployment_time=60.0)
    result = search(catalogue, paper_system().load, requirements)
    (cc16,) = [
        c
        for c in result.candidates
        if c.candidate.damper.name == "CDA Cc-16 damper"
        and c.candidate.gearbox.name == "CDA Cc-16 gearbox"
    ]
    # tests/hand.py types Eq. 1-4 and the exact time from the paper's constants.
    for i, t in enumerate(PAPER_TEMPS):
        assert cc16.deployment_time[i] == pytest.approx(hand.exact_time(t), rel=1e-12)
        assert cc16.damping_rate[i] == pytest.approx(hand.becd(t), rel=1e-12)
        assert cc16.friction[i] == pytest.approx(hand.fecd(t), rel=1e-12)
    worst = hand.exact_time(-40.0)  # coldest is slowest: 48.13 s
    (check,) = [o for o in cc16.checks if o.name == "max_deployment_time"]
    assert check.temperature_C == -40.0
    assert check.margin == pytest.approx(60.0 / worst - 1.0, rel=1e-12)
    assert cc16.spread == pytest.approx(worst - hand.exact_time(100.0), rel=1e-12)
    assert cc16.passed


MIXED = """
[[damper]]
name = "rated at 20 degC, tabulated lubrication"
source = "test"
damping_rate = "1.1e-4 N*m*s/rad"
reference_temperature = "20 degC"
damping_temperature_coefficient = "-0.003 / K"
coulomb_friction = "6e-4 N*m"
lubrication_friction = { table = [["-50 degC", "4e-4 N*m"], ["0 degC", "2e-4 N*m"],
                                  ["80 degC", "1e-4 N*m"]] }

[[damper]]
name = "paper damper"
source = "test"
damping_rate = "1.3e-4 N*m*s/rad"
coulomb_friction = "7.9e-4 N*m"
lubrication_friction = { slope = "-2.12e-6 N*m/K", at_0C = "2.2e-4 N*m" }

[[gearbox]]
name = "fraction"
source = "test"
ratios = [250, 380, 600]
damping_fraction = 0.26
coulomb_friction = "4.5e-4 N*m"

[[gearbox]]
name = "value"
source = "test"
ratios = [300]
damping_rate = "3e-5 N*m*s/rad"
coulomb_friction = "3e-4 N*m"
"""


def test_vectorised_search_equals_scalar_prediction_of_every_candidate() -> None:
    # The reference: each candidate built as its own scalar system and run through
    # deployment.predict, without the stacking and re-referencing of the search.
    catalogue = parse_toml_catalogue(MIXED)
    load = paper_system().load
    temps = (-40.0, 0.0, 25.0, 100.0)
    result = search(catalogue, load, Requirements(temps, no_stall=False))
    assert len(result.candidates) == 2 * 4
    for row in result.candidates:
        system = DeploymentSystem(row.candidate.ecd(), load)
        alone = predict(system, temps, ("exact",))
        exact = alone.solutions["exact"]
        # The re-referred damping law differs from the original by rounding only.
        np.testing.assert_allclose(row.deployment_time, exact.deployment_time, rtol=1e-12)
        np.testing.assert_allclose(row.end_speed, exact.end_speed, rtol=1e-12)
        np.testing.assert_allclose(row.damping_rate, alone.ecd.ecd_damping_rate, rtol=1e-12)
        np.testing.assert_allclose(row.friction, alone.ecd.ecd_friction, rtol=1e-12)
        assert row.stalled == tuple(bool(s) for s in exact.stalled)
    candidates = [r.candidate for r in result.candidates]
    curves = deployment_time_curves(candidates, load, temps)
    np.testing.assert_allclose(curves, [r.deployment_time for r in result.candidates], rtol=0)


def result_for(mass: float | None, passed: bool, margin: float, spread: float) -> CandidateResult:
    catalogue = parse_toml_catalogue(MIXED)
    damper = catalogue.dampers[0]
    gearbox = catalogue.gearboxes[0]
    if mass is not None:
        from dataclasses import replace

        damper = replace(damper, mass=mass)
        gearbox = replace(gearbox, mass=0.0)
    return CandidateResult(Candidate(damper, gearbox, 100.0), 0, passed, margin, spread, (), ())


def test_rank_key_orders_pass_mass_margin_spread() -> None:
    rows = {
        "fails, lightest": result_for(0.05, False, 0.5, 1.0),
        "heavy": result_for(0.30, True, 0.9, 1.0),
        "light, small margin": result_for(0.10, True, 0.1, 1.0),
        "light, large margin, big spread": result_for(0.10, True, 0.4, 9.0),
        "light, large margin, small spread": result_for(0.10, True, 0.4, 2.0),
        "mass unknown": result_for(None, True, 0.9, 1.0),
    }
    order = sorted(rows, key=lambda k: rank_key(rows[k]))
    assert order == [
        "light, large margin, small spread",
        "light, large margin, big spread",
        "light, small margin",
        "heavy",
        "mass unknown",
        "fails, lightest",
    ]


def test_example_ranking_and_json() -> None:
    catalogue = load_catalogue(ROOT / "examples" / "catalogue.toml")
    requirements = Requirements(
        PAPER_TEMPS, min_deployment_time=10.0, max_deployment_time=60.0, max_end_speed=0.1
    )
    result = search(catalogue, paper_system().load, requirements)
    assert len(result.candidates) == len(catalogue_candidates(catalogue)) == 3 * 6
    assert [c.rank for c in result.candidates] == list(range(1, 19))
    passed = [c.passed for c in result.candidates]
    assert passed == sorted(passed, reverse=True)  # every pass before every fail
    masses = [c.candidate.mass for c in result.candidates if c.passed]
    known = [m for m in masses if m is not None]
    assert masses == sorted(known) + [None] * (len(masses) - len(known))  # unknown last
    document = json.loads(json.dumps(result.to_dict(), allow_nan=False))
    first = document["candidates"][0]
    assert set(first) >= {"rank", "damper", "gearbox", "ratio", "passed", "margin", "checks"}
    assert set(first["checks"]) >= {"min_deployment_time", "max_deployment_time", "no_stall"}
    flags = {(c["damper"], c["gearbox"]): c["illustrative"] for c in document["candidates"]}
    assert flags[("CDA Cc-16 damper", "CDA Cc-16 gearbox")] is False
    assert all(v for k, v in flags.items() if "Demo" in k[0] or "Demo" in k[1])
    assert document["illustrative_label"] == "illustrative, not vendor data"


def test_candidate_outside_its_damping_law_is_reported_not_fatal() -> None:
    # -0.02 /K from 25 degC reaches BD_T = 0 at 75 degC: no model at 100 degC.
    text = MIXED.replace('"-0.003 / K"', '"-0.02 / K"')
    result = search(parse_toml_catalogue(text), paper_system().load, Requirements(PAPER_TEMPS))
    broken = [c for c in result.candidates if c.error is not None]
    assert len(broken) == 4  # the first damper with each of the 4 gearbox ratios
    assert all("BECD <= 0 at 100 degC" in (c.error or "") for c in broken)
    assert all(c.rank > 4 for c in broken)  # ranked last
    json.dumps(result.to_dict(), allow_nan=False)


def test_extrapolated_and_non_physical_inputs_are_flagged() -> None:
    # The first damper's lubrication table ends at 80 degC; the paper's FS_T = 0.58 -
    # 0.0044 T turns negative above 131.8 degC.
    result = search(
        parse_toml_catalogue(MIXED), paper_system().load, Requirements((25.0, 100.0, 140.0))
    )
    for row in result.candidates:
        tabulated = row.candidate.damper.name.startswith("rated at 20")
        assert ("lubrication friction table extrapolated at 100 degC" in row.warnings) is tabulated
        assert ("lubrication friction table extrapolated at 140 degC" in row.warnings) is tabulated
        assert "FS < 0 (friction law outside its range) at 140 degC" in row.warnings
        assert not any("25 degC" in w for w in row.warnings)
        assert row.to_dict()["warnings"] == list(row.warnings)
