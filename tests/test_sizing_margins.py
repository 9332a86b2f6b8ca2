"""Sizing defects of issue 11, item 5, each against a hand calculation from the paper.

(a) a mechanism that cannot start has no running input torque: "cannot start", never the
    damper's friction capacity; (c) an unknown catalogue mass stays unknown; (d) the
    torque margin of ECSS-E-ST-33-01C's form, per temperature, with its resistive torques
    split by kind. Item (b) (separate static factors) is in tests/test_sizing_static.py.

The paper's numbers (section 6): BD = 1.3e-4 N*m*s/rad (-0.4 %/K from 25 degC, Eq. 1),
BG = 0.26 BD, FD = 7.9e-4 N*m, FL_T = -2.12e-6 T + 2.2e-4 N*m, FG = 4.5e-4 N*m,
Ts = 3.73 N*m, Te = 1.58 N*m over 1.57 rad, FS_T = -0.0044 T + 0.58 N*m.
"""

from __future__ import annotations

import json
import math

import numpy as np
import pytest

from ecdsim.config import ConfigError
from ecdsim.sizing.catalogue import load_catalogue, parse_csv_catalogue, parse_toml_catalogue
from ecdsim.sizing.margin import MarginSettings
from ecdsim.sizing.ratio import ratio_intervals
from ecdsim.sizing.requirements import Requirements
from ecdsim.sizing.search import CandidateResult, search
from tests import hand
from tests.conftest import ROOT, paper_system

CATALOGUE = ROOT / "examples" / "catalogue.toml"
# The code and the hand formulas do the same few float operations on O(1) numbers: they
# agree to rounding, 1e-12 relative.
TIGHT = 1e-12


def ft(t: float) -> float:
    """FT_T = FD + FL_T + FG at the high-speed shaft (Eq. 2) [N*m]."""
    return 7.9e-4 + (-2.12e-6 * t + 2.2e-4) + 4.5e-4


def only(result_candidates: tuple[CandidateResult, ...], damper: str, gearbox: str,
         ratio: float) -> CandidateResult:  # fmt: skip
    (found,) = [
        c
        for c in result_candidates
        if c.candidate.damper.name == damper
        and c.candidate.gearbox.name == gearbox
        and c.candidate.ratio == ratio
    ]
    return found


# (a) ---------------------------------------------------------------------------------

CC16_2600 = """
[[damper]]
name = "CDA Cc-16 damper"
source = "paper section 6"
damping_rate = "1.3e-4 N*m*s/rad"
coulomb_friction = "7.9e-4 N*m"
lubrication_friction = { slope = "-2.12e-6 N*m/K", at_0C = "2.2e-4 N*m" }
max_torque = "0.5 N*m"

[[gearbox]]
name = "Cc-16 gearbox, more ratios"
source = "paper section 6, ratios invented for the test"
ratios = [380, 2600]
damping_fraction = 0.26
coulomb_friction = "4.5e-4 N*m"
max_output_torque = "3.5 N*m"
"""


def test_a_mechanism_that_cannot_start_reports_cannot_start() -> None:
    # 2600:1 at -40 degC: FECD = 2600 * FT(-40) = 2600 * 1.5448e-3 = 4.016 N*m, more than
    # the spring's whole 3.73 N*m, and Ts - FS(-40) = 3.73 - 0.756 = 2.974 N*m < FECD:
    # Eq. 8 gives a negative start speed, the spring cannot start the deployment. The ECD
    # can then never see its friction capacity 4.016 N*m (which today's code compared
    # with the 4 N*m limit and failed): it holds 2.974 N*m at most.
    fecd = 2600.0 * ft(-40.0)
    held = hand.TS - hand.fs(-40.0)
    assert fecd == pytest.approx(4.01648, rel=TIGHT)
    assert held == pytest.approx(2.974, rel=TIGHT)
    requirements = Requirements((-40.0,), max_input_torque=4.0)
    result = search(parse_toml_catalogue(CC16_2600), paper_system().load, requirements)
    stuck = only(result.candidates, "CDA Cc-16 damper", "Cc-16 gearbox, more ratios", 2600.0)
    assert stuck.cannot_start == (True,)
    assert stuck.stalled == (True,)
    checks = {o.name: o for o in stuck.checks}
    torque = checks["max_input_torque"]
    assert torque.cannot_start
    assert torque.result == "cannot start"
    assert torque.margin == pytest.approx((4.0 - held) / 4.0, rel=TIGHT)
    assert torque.to_dict()["value"] is None
    assert torque.to_dict()["cannot_start"] is True
    # The gearbox's output torque is the same input torque: also "cannot start".
    assert checks["gearbox_max_output_torque"].result == "cannot start"
    assert checks["no_stall"].result == "FAIL"  # what really fails the design
    (case,) = stuck.to_dict()["cases"]
    assert case["input_torque_Nm"] is None
    assert case["cannot_start"] is True
    # At 380:1 the mechanism runs: its input torque is Ts - FS (Eq. 5 at the start).
    runs = only(result.candidates, "CDA Cc-16 damper", "Cc-16 gearbox, more ratios", 380.0)
    assert runs.cannot_start == (False,)
    assert runs.input_torque[0] == pytest.approx(held, rel=TIGHT)
    assert {o.name: o for o in runs.checks}["max_input_torque"].result == "pass"


def test_input_torque_does_not_limit_the_gear_ratio() -> None:
    # Today the input-torque check failed above N = 4 / FT(-40) = 2589.3 (FECD > 4 N*m),
    # where the mechanism cannot start. The torque the ECD holds or passes is Ts - FS_T at
    # most, 2.974 N*m < 4 N*m at -40 degC (3.59 at 100 degC): no ratio fails the check.
    catalogue = load_catalogue(CATALOGUE)
    requirements = Requirements((-40.0, 100.0), max_input_torque=4.0, ratio_range=(10.0, 5000.0))
    found = ratio_intervals(
        catalogue.damper("CDA Cc-16 damper"),
        catalogue.gearbox("CDA Cc-16 gearbox"),
        paper_system().load,
        requirements,
        n_grid=60,
    )
    (interval,) = found.by_check["max_input_torque"]
    assert (interval.low, interval.high) == (10.0, 5000.0)
    assert (interval.low_limited_by, interval.high_limited_by) == ("scan range", "scan range")
    # The no-stall limit is where the start is lost at -40 degC: (Te - FS)/FT, as before.
    (stall,) = found.by_check["no_stall"]
    assert stall.high == pytest.approx((hand.TE - hand.fs(-40.0)) / ft(-40.0), rel=1e-9)


# (c) ---------------------------------------------------------------------------------


def test_unknown_masses_stay_unknown_and_rank_after_known_ones() -> None:
    catalogue = load_catalogue(CATALOGUE)
    requirements = Requirements((-40.0, 25.0, 100.0), max_deployment_time=200.0, no_stall=False)
    result = search(catalogue, paper_system().load, requirements)
    masses = {
        (c.candidate.damper.name, c.candidate.gearbox.name): c.candidate.mass
        for c in result.candidates
    }
    # The paper gives only the Cc-16 assembly's 0.185 kg: with its own gearbox the mass is
    # known, with any other it is not; the Cc-16 gearbox has no mass of its own (today it
    # was entered as 0 kg, so "Demo damper S + Cc-16 gearbox" ranked at 0.07 kg).
    assert masses[("CDA Cc-16 damper", "CDA Cc-16 gearbox")] == pytest.approx(0.185, rel=TIGHT)
    assert masses[("CDA Cc-16 damper", "Demo planetary")] is None
    assert masses[("Demo damper S", "CDA Cc-16 gearbox")] is None
    assert masses[("Demo damper L", "CDA Cc-16 gearbox")] is None
    assert masses[("Demo damper S", "Demo planetary")] == pytest.approx(0.07 + 0.05, rel=TIGHT)
    for passed in (True, False):
        group = [c.candidate.mass for c in result.candidates if c.passed is passed]
        known = [m for m in group if m is not None]
        assert known == sorted(known)
        assert group == known + [None] * (len(group) - len(known))  # unknown last
    document = json.loads(json.dumps(result.to_dict(), allow_nan=False))
    rows = {(c["damper"], c["gearbox"], c["ratio"]): c for c in document["candidates"]}
    unknown = rows[("Demo damper S", "CDA Cc-16 gearbox", 380.0)]
    assert unknown["mass_kg"] is None
    assert unknown["mass_known"] is False
    assert "no mass for gearbox 'CDA Cc-16 gearbox'" in unknown["mass_note"]
    assembly = rows[("CDA Cc-16 damper", "CDA Cc-16 gearbox", 380.0)]
    assert assembly["mass_known"] is True
    assert "assembly mass" in assembly["mass_note"]


@pytest.mark.parametrize(
    ("text", "fragment"),
    [
        ('[[gearbox]]\nname = "G"\nsource = "s"\nratios = [10]\ndamping_fraction = 0.2\n'
         'coulomb_friction = "1e-4 N*m"\nmass = "0 kg"\n',
         "gearbox #1 'G': mass: '0 kg' must be > 0 (leave mass out if it is not known); "
         "expected a mass in kg"),
        ('[[gearbox]]\nname = "G"\nsource = "s"\nratios = [10]\ndamping_fraction = 0.2\n'
         'coulomb_friction = "1e-4 N*m"\n'
         '[[damper]]\nname = "D"\nsource = "s"\ndamping_rate = "1e-4 N*m*s/rad"\n'
         'coulomb_friction = "1e-4 N*m"\nmass = "0.1 kg"\nmass_includes_gearbox = "H"\n',
         "damper 'D': mass_includes_gearbox: no gearbox 'H' in the catalogue"),
        ('[[gearbox]]\nname = "G"\nsource = "s"\nratios = [10]\ndamping_fraction = 0.2\n'
         'coulomb_friction = "1e-4 N*m"\n'
         '[[damper]]\nname = "D"\nsource = "s"\ndamping_rate = "1e-4 N*m*s/rad"\n'
         'coulomb_friction = "1e-4 N*m"\nmass_includes_gearbox = "G"\n',
         "damper #1 'D': (entry): mass_includes_gearbox needs mass"),
    ],
)  # fmt: skip
def test_bad_masses_are_one_line_errors(text: str, fragment: str) -> None:
    with pytest.raises(ConfigError) as raised:
        parse_toml_catalogue(text)
    assert any(fragment in line for line in raised.value.problems), raised.value.problems
    assert all("\n" not in line for line in raised.value.problems)


def test_assembly_mass_from_csv() -> None:
    text = (
        "kind,name,source,damping_rate [N*m*s/rad],coulomb_friction [N*m],mass [kg],"
        "mass_includes_gearbox,ratios,damping_fraction\n"
        "damper,D,s,1e-4,1e-4,0.2,G,,\n"
        "gearbox,G,s,,1e-4,,,100,0.2\n"
        "gearbox,H,s,,1e-4,0.05,,100,0.2\n"
    )
    catalogue = parse_csv_catalogue(text)
    assert catalogue.damper("D").mass_includes_gearbox == "G"
    result = search(catalogue, paper_system().load, Requirements((25.0,), no_stall=False))
    masses = {c.candidate.gearbox.name: c.candidate.mass for c in result.candidates}
    assert masses == {"G": pytest.approx(0.2, rel=TIGHT), "H": None}
    assert [c.candidate.gearbox.name for c in result.candidates] == ["G", "H"]


# (d) ---------------------------------------------------------------------------------


def hand_margin(t: float, speed: float, f_ecd: float = 1.0, f_sys: float = 1.0,
                f_damp: float = 1.0) -> float:  # fmt: skip
    """ECSS-E-ST-33-01C form by hand, at the end of travel (the spring's lowest torque,
    where every resistive torque is the same as anywhere else): TM = Te / (f_E FECD_T +
    f_S FS_T + f_D BECD_T w) - 1."""
    resist = f_ecd * hand.fecd(t) + f_sys * hand.fs(t) + f_damp * hand.becd(t) * speed
    return hand.TE / resist - 1.0


def test_example_margins_per_temperature_split_by_kind() -> None:
    # The shipped example: damping at 0.005 rad/s, no factors. By hand at -40 degC:
    # 1.58 / (0.58702 + 0.756 + 28.5334 * 0.005) - 1 = 1.58 / 1.48569 - 1 = 0.0635;
    # 25 degC: 1.58 / (0.53466 + 0.47 + 0.11826) - 1 = 0.407; 100 degC: 1.243.
    from ecdsim.config import load_config

    config = load_config(ROOT / "examples" / "sizing.toml")
    assert config.spec.requirements is not None
    requirements = Requirements.from_spec(config.spec.requirements)
    result = search(load_catalogue(CATALOGUE), config.system.load, requirements)
    cc16 = only(result.candidates, "CDA Cc-16 damper", "CDA Cc-16 gearbox", 380.0)
    temps = (-40.0, 25.0, 100.0)
    assert [m.temperature_C for m in cc16.torque_margins] == list(temps)
    for margin, t in zip(cc16.torque_margins, temps, strict=True):
        assert margin.margin == pytest.approx(hand_margin(t, 0.005), rel=TIGHT)
        assert margin.angle == pytest.approx(hand.TRAVEL, rel=TIGHT)  # end of travel
        assert margin.drive == pytest.approx(hand.TE, rel=TIGHT)
        assert margin.resistive["ecd_friction"] == pytest.approx(hand.fecd(t), rel=TIGHT)
        assert margin.resistive["system_friction"] == pytest.approx(hand.fs(t), rel=TIGHT)
        assert margin.resistive["damping"] == pytest.approx(hand.becd(t) * 0.005, rel=TIGHT)
        assert margin.factored == pytest.approx(hand.TE / (1.0 + margin.margin), rel=TIGHT)
    values = [m.margin for m in cc16.torque_margins]
    assert values == pytest.approx([0.0635, 0.407, 1.243], abs=5e-4)  # the figures above
    assert all(v > 0.0 for v in values)
    assert cc16.torque_margin == pytest.approx(min(values), rel=TIGHT)
    cases = cc16.to_dict()["cases"]
    assert cases[0]["torque_margin"]["resistive_Nm"]["system_friction"] == pytest.approx(
        hand.fs(-40.0), rel=TIGHT
    )
    assert set(cases[0]["torque_margin"]) == {
        "margin", "angle_rad", "drive_Nm", "resistive_Nm", "factored_resistance_Nm"
    }  # fmt: skip


def test_each_friction_kind_has_its_own_factor() -> None:
    from ecdsim.sizing.margin import factor_of

    catalogue = load_catalogue(CATALOGUE)
    settings = MarginSettings(
        factors={"ecd_friction": 1.5, "system_friction": 1.2, "damping": 1.1},
        damping_speed=0.005,
    )
    requirements = Requirements((-40.0, 100.0), no_stall=False, margin=settings)
    result = search(catalogue, paper_system().load, requirements)
    cc16 = only(result.candidates, "CDA Cc-16 damper", "CDA Cc-16 gearbox", 380.0)
    for margin, t in zip(cc16.torque_margins, (-40.0, 100.0), strict=True):
        expected = hand_margin(t, 0.005, f_ecd=1.5, f_sys=1.2, f_damp=1.1)
        assert margin.margin == pytest.approx(expected, rel=TIGHT)
        # The unfactored terms stay as they are; only their sum is factored.
        assert margin.resistive["ecd_friction"] == pytest.approx(hand.fecd(t), rel=TIGHT)
    # `friction` is the factor of both Coulomb kinds unless one is given on its own.
    assert factor_of("system_friction", {"friction": 1.3}) == 1.3
    assert factor_of("ecd_friction", {"friction": 1.3, "ecd_friction": 2.0}) == 2.0
    assert factor_of("damping", {"friction": 1.3}) == 1.0
    with pytest.raises(KeyError, match="unknown uncertainty factor"):
        factor_of("damping", {"wind": 2.0})


def test_default_margin_has_no_damping_and_equals_the_stall_margin() -> None:
    # Without a damping speed the damping term is 0 (speed 0): with unit factors the
    # margin at the end of travel is Te / (FECD + FS) - 1, the no-stall margin
    # (Te - F) / F exactly (they are the same quotient). Today the default took the
    # deployment's own speed, where the margin is 0 by quasi-static equilibrium.
    requirements = Requirements((-40.0, 25.0, 100.0))
    assert requirements.margin.damping_mode == "none"
    result = search(load_catalogue(CATALOGUE), paper_system().load, requirements)
    cc16 = only(result.candidates, "CDA Cc-16 damper", "CDA Cc-16 gearbox", 380.0)
    stall = {o.name: o for o in cc16.checks}["no_stall"]
    for margin, t in zip(cc16.torque_margins, (-40.0, 25.0, 100.0), strict=True):
        assert margin.margin == pytest.approx(hand_margin(t, 0.0), rel=TIGHT)
        assert margin.resistive["damping"] == 0.0
    assert cc16.torque_margin == pytest.approx(stall.margin, rel=TIGHT)


def test_config_damping_speed_and_friction_factors() -> None:
    from ecdsim.config import parse_config
    from tests.conftest import PAPER_CONFIG

    base = PAPER_CONFIG.read_text() + '\n[requirements]\ntemperatures = ["25 degC"]\n'
    default = parse_config(base)
    assert default.spec.requirements is not None
    assert Requirements.from_spec(default.spec.requirements).margin.damping_speed == 0.0
    split = parse_config(
        base + "[requirements.torque_margin]\n"
        'damping_speed = "0 rad/s"\nfactors = { friction = 1.4, system_friction = 2 }\n'
    )
    assert split.spec.requirements is not None
    factors = Requirements.from_spec(split.spec.requirements).margin.factors
    assert factors["ecd_friction"] == 1.4
    assert factors["system_friction"] == 2.0
    with pytest.raises(ConfigError) as raised:
        parse_config(base + '[requirements.torque_margin]\ndamping_speed = "-1 rad/s"\n')
    (line,) = raised.value.problems
    assert "requirements.torque_margin.damping_speed" in line
    assert "must be >= 0" in line
    assert "expected an angular speed in rad/s" in line


def test_torque_margin_is_exact_between_breakpoints_with_split_frictions() -> None:
    # Brute force over 20001 angles of a three-point spring with a stall, the two
    # frictions factored apart.
    from ecdsim.sizing.margin import margin_over_travel

    angles = np.array([0.0, 0.4, 1.0])
    torques = np.array([1.0, 0.9, 0.1])
    fecd, fs, damping = 0.2, 0.1, 2.0
    factors = {"ecd_friction": 1.5, "system_friction": 1.25, "damping": 1.2}
    stall = 0.4 + 0.6 * (0.9 - 0.3) / (0.9 - 0.1)
    over = margin_over_travel(
        angles, torques, ecd_friction=fecd, system_friction=fs, damping_rate=damping,
        stalled=True, stall_angle=stall, settings=MarginSettings(factors, {}, None),
    )  # fmt: skip
    terms = over.at_minimum()
    phi = np.linspace(0.0, 1.0, 20001)
    spring = np.interp(phi, angles, torques)
    omega = np.maximum(spring - fecd - fs, 0.0) / damping
    brute = spring / (1.5 * fecd + 1.25 * fs + 1.2 * damping * omega) - 1.0
    assert float(terms.margin) == pytest.approx(brute.min(), rel=TIGHT)
    assert float(terms.margin) == pytest.approx(0.1 / (0.3 + 0.125) - 1.0, rel=TIGHT)
    assert float(terms.angle) == 1.0
    assert float(terms.drive) == pytest.approx(0.1, rel=TIGHT)
    assert float(terms.factored) == pytest.approx(0.425, rel=TIGHT)
    assert math.isclose(float(terms.resistive["damping"]), 0.0, abs_tol=0.0)  # stalled there
