"""The wing file (ecdsim.config.wing_schema) and the wing model (ecdsim.wing.model).

A wing file reuses the single hinge's sections, so its hinges must evaluate to the same
numbers as the single hinge's config with the same keys; a one-panel wing is today's
hinge (the same prediction, bit for bit, from the hand-written single-hinge file whose
inertia is the panel's about the hinge, worked out here). Bad files get one line per
problem naming the key path, the value and the expected unit.
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest
from typer.testing import CliRunner

from ecdsim.cli.app import app
from ecdsim.config import ConfigError, load_config, parse_config
from ecdsim.config.wing_schema import describe_wing_field, load_wing_config, parse_wing_config
from ecdsim.deployment import predict
from ecdsim.sizing.catalogue import load_catalogue
from ecdsim.wing import Cable, Latch

ROOT = Path(__file__).resolve().parent.parent
EXAMPLE = ROOT / "examples" / "wing_cc16_three_panel.toml"
PAPER = ROOT / "examples" / "paper_cc16.toml"

CC16 = """
[wing.ecds.cc16.damper]
damping_rate = "1.3e-4 N*m*s/rad"
reference_temperature = "25 degC"
damping_temperature_coefficient = "-0.004 / K"
coulomb_friction = "7.9e-4 N*m"
lubrication_friction = { slope = "-2.12e-6 N*m/K", at_0C = "2.2e-4 N*m" }
rotor_inertia = "2e-7 kg*m^2"
[wing.ecds.cc16.gearbox]
ratio = 380
damping_fraction = 0.26
coulomb_friction = "4.5e-4 N*m"
"""

PANEL = """
[[wing.panels]]
mass = "2 kg"
length = "0.8 m"
cg_along = "0.3 m"
cg_across = "0.04 m"
inertia = "0.1 kg*m^2"
"""

HINGE = """
[[wing.hinges]]
stowed_angle = "{stowed}"
deployed_angle = "{deployed}"
start_torque = "3.73 N*m"
end_torque = "1.58 N*m"
friction = {{ slope = "-0.0044 N*m/K", at_0C = "0.58 N*m" }}
ecd = "{ecd}"
"""


def _wing_text(*hinges: tuple[str, str], ecd: str = "cc16", extra: str = "") -> str:
    text = CC16 + PANEL * len(hinges)
    for stowed, deployed in hinges:
        text += HINGE.format(stowed=stowed, deployed=deployed, ecd=ecd)
    return text + extra


def test_the_example_reads_and_its_hinges_are_the_papers_ecd() -> None:
    config = load_wing_config(EXAMPLE)
    wing = config.wing
    assert config.temperatures == (-40.0, 25.0, 100.0)
    assert [h.name for h in wing.hinges] == ["root", "middle", "outer"]
    np.testing.assert_allclose(wing.travels, [math.pi / 2, math.pi, math.pi], rtol=1e-15)
    np.testing.assert_array_equal(wing.directions, [-1.0, 1.0, -1.0])
    paper = load_config(PAPER).system
    temperatures = np.array([-40.0, 25.0, 100.0])
    single = paper.ecd.at(temperatures)
    friction = paper.load.system_friction(temperatures)
    for state in wing.at(temperatures).hinges:
        # Eq. 1-4 and FS_T by the same model calls: the single hinge's numbers exactly.
        np.testing.assert_array_equal(state.damping_rate, single.ecd_damping_rate)
        np.testing.assert_array_equal(state.ecd_friction, single.ecd_friction)
        np.testing.assert_array_equal(state.hinge_friction, friction)
        np.testing.assert_array_equal(state.kinetic_friction, single.ecd_friction + friction)
    # The paper's printed values at +25 degC (section 6: 24 and 0.52; docs/model.md).
    state = wing.hinges[0].at(25.0)
    assert float(state.damping_rate) == pytest.approx(23.65272, rel=1e-12)
    assert float(state.ecd_friction) == pytest.approx(0.53466, rel=1e-12)
    # Rotor reflected through 380:1: 2e-7 * 380^2.
    assert wing.hinges[0].ecd is not None
    assert wing.hinges[0].ecd.reflected_inertia == pytest.approx(2e-7 * 380**2, rel=1e-15)


def test_stowed_z_fold_and_deployed_line() -> None:
    wing = load_wing_config(EXAMPLE).wing
    outlines = wing.outlines(np.zeros(3))
    # Stowed: the three panels lie on the side (x = 0), stacked between y = 0 and 0.5 m.
    centre_lines = (outlines[:, 0] + outlines[:, 3]) / 2, (outlines[:, 1] + outlines[:, 2]) / 2
    np.testing.assert_allclose(centre_lines[0][:, 0], 0.0, atol=1e-15)
    np.testing.assert_allclose(centre_lines[1][:, 0], 0.0, atol=1e-15)
    # Deployed: in line along +x, the tip at 1.5 m.
    deployed = wing.outlines(wing.travels)
    tip = (deployed[2, 1] + deployed[2, 2]) / 2
    np.testing.assert_allclose(tip, [1.5, 0.0], atol=1e-15)


def test_one_panel_wing_is_todays_hinge() -> None:
    # The same hinge written as a single-hinge file: load inertia about the hinge by the
    # parallel-axis theorem, I + m (a^2 + b^2) = 0.1 + 2 (0.3^2 + 0.04^2) = 0.2832.
    text = PAPER.read_text(encoding="utf-8")
    text = text.replace('travel = "1.57 rad"', 'travel = "90 deg"\ninertia = "0.2832 kg*m^2"')
    damper = 'coulomb_friction = "7.9e-4 N*m"'
    text = text.replace(damper, damper + '\nrotor_inertia = "2e-7 kg*m^2"', 1)
    single = parse_config(text)
    dynamics = single.spec.dynamics()
    assert dynamics is not None
    wing = parse_wing_config(_wing_text(("90 deg", "0 deg"))).wing
    system, params = wing.as_single_hinge()
    assert params.load_inertia == pytest.approx(0.2832, rel=1e-15)
    temperatures = [-40.0, 25.0, 100.0]
    expected = predict(single.system, temperatures, ["exact", "dynamic"], dynamics=dynamics)
    got = predict(system, temperatures, ["exact", "dynamic"], dynamics=params)
    for method in ("exact", "dynamic"):
        np.testing.assert_allclose(
            got.solutions[method].deployment_time,
            expected.solutions[method].deployment_time,
            rtol=1e-15,  # the same inputs to the same code: the same numbers
        )
    assert got.solutions["dynamic"].deployment_time[1] == pytest.approx(26.5, rel=0.05)


def test_one_panel_ground_test_maps_onto_load_gravity() -> None:
    # Gravity along -y; the panel stowed at 90 deg with its CG at (a, b) = (0.3, 0.04) m,
    # deploying clockwise (s = -1). The CG line is at 90 + atan2(0.04, 0.3) deg; from the
    # downward vertical (-90 deg), counted in the direction of deployment (clockwise):
    # -(90 + 7.595 + 90) = -187.595 deg = 172.405 deg after wrapping.
    extra = '[wing.ground_test]\ngravity_direction = "-90 deg"\noffload = "75 %"\n'
    wing = parse_wing_config(_wing_text(("90 deg", "0 deg"), extra=extra)).wing
    system, _ = wing.as_single_hinge()
    gravity = system.load.gravity
    assert gravity is not None
    beta = math.degrees(math.atan2(0.04, 0.3))
    assert math.degrees(float(gravity.release_angle)) == pytest.approx(
        360.0 - (180.0 + beta), rel=1e-13
    )
    assert float(gravity.cg_radius) == pytest.approx(math.hypot(0.3, 0.04), rel=1e-15)
    assert float(gravity.offload) == 0.75
    # The single hinge's gravity torque equals minus the chain's generalised force on
    # the deployed angle (phi = s (q - q_stowed)), at any angle.
    from ecdsim.physics import chain

    arrays = wing.chain_arrays()
    gx, gy = wing.ground_test.gravity if wing.ground_test else (0.0, 0.0)
    for phi in (0.0, 0.4, 1.2):
        q = wing.relative_angles(np.array([phi]))
        force = chain.gravity_forces(
            q,
            arrays["mass"],
            arrays["cg_along"],
            arrays["cg_across"],
            arrays["length"],
            arrays["offload"],
            gx,
            gy,
        )
        opposing = float(gravity.torque_at(phi))
        assert wing.directions[0] * force[0] == pytest.approx(-opposing, abs=1e-13)


def test_catalogue_entry_is_the_inline_ecd() -> None:
    inline = parse_wing_config(_wing_text(("0 deg", "90 deg"))).wing
    catalogued = parse_wing_config(
        _wing_text(("0 deg", "90 deg")).replace(CC16, "")
        + '[wing.ecds.cc16.catalogue]\nfile = "catalogue.toml"\n'
        'damper = "CDA Cc-16 damper"\ngearbox = "CDA Cc-16 gearbox"\nratio = 380\n',
        base=ROOT / "examples",
        read_catalogue=load_catalogue,
    ).wing
    temperatures = np.array([-40.0, 25.0, 100.0])
    a, b = inline.hinges[0].at(temperatures), catalogued.hinges[0].at(temperatures)
    np.testing.assert_array_equal(a.damping_rate, b.damping_rate)
    np.testing.assert_array_equal(a.ecd_friction, b.ecd_friction)
    assert catalogued.hinges[0].ecd is not None
    assert "CDA Cc-16 damper" in catalogued.hinges[0].ecd.source


def test_catalogue_problems() -> None:
    text = (
        _wing_text(("0 deg", "90 deg")).replace(CC16, "")
        + '[wing.ecds.cc16.catalogue]\nfile = "catalogue.toml"\n'
        'damper = "CDA Cc-16 damper"\ngearbox = "CDA Cc-16 gearbox"\nratio = 100\n'
    )
    with pytest.raises(ConfigError) as caught:
        parse_wing_config(text, "w.toml", ROOT / "examples", load_catalogue)
    assert caught.value.problems == [
        "wing.ecds.cc16.catalogue.ratio: 100 is not a ratio of 'CDA Cc-16 gearbox' (it "
        "offers [380.0])"
    ]
    with pytest.raises(ConfigError) as caught:
        parse_wing_config(text, "w.toml")
    assert "need a catalogue reader" in caught.value.problems[0]


def test_cables_latches_and_names() -> None:
    extra = (
        "[[wing.cables]]\nhinges = [1, 2]\nratio = 2\n"
        '[[wing.cables]]\nhinges = [2, 3]\nratio = 1\nstiffness = "500 N*m/rad"\n'
        'pretension = "150 N"\npulley_radius = "20 mm"\n'
    )
    text = _wing_text(("90 deg", "0 deg"), ("-180 deg", "0 deg"), ("180 deg", "0 deg"), extra=extra)
    text = text.replace(
        'ecd = "cc16"\n',
        'ecd = "cc16"\nlatch = { stiffness = "2000 N*m/rad", damping = "3 N*m*s/rad" }\n',
        1,
    )
    wing = parse_wing_config(text).wing
    assert wing.cables == (
        Cable(inboard=0, ratio=2.0),
        Cable(inboard=1, ratio=1.0, stiffness=500.0, slack_torque=2 * 150.0 * 0.02),
    )
    assert wing.hinges[0].latch == Latch(stiffness=2000.0, damping=3.0)
    assert wing.hinges[1].latch == Latch()
    assert [p.name for p in wing.panels] == ["panel 1", "panel 2", "panel 3"]
    assert [h.name for h in wing.hinges] == ["hinge 1", "hinge 2", "hinge 3"]
    undamped = parse_wing_config(_wing_text(("0 deg", "1 rad"), ecd="none")).wing
    assert undamped.hinges[0].ecd is None
    assert float(undamped.hinges[0].at(25.0).damping_rate) == 0.0


def test_field_errors_are_one_line_each_with_the_unit() -> None:
    text = _wing_text(("90 deg", "0 deg"))
    text = text.replace('damping_rate = "1.3e-4 N*m*s/rad"', 'damping_rate = "1.3e-4 N*m"')
    text = text.replace('mass = "2 kg"\n', "")
    text = text.replace('length = "0.8 m"', 'length = "0.8"')
    text = text.replace("damping_fraction = 0.26", "damping_fraction = 0.26\ncolour = 'red'")
    text += "[wing.ground_test]\ngravity_direction = '-90 deg'\noffload = '120 %'\n"
    text += "[[wing.cables]]\nhinges = [1, 3]\nratio = 1\npretension = '10 N'\n"
    with pytest.raises(ConfigError) as caught:
        parse_wing_config(text, "w.toml")
    known = "ratio, damping_fraction, damping_rate, coulomb_friction, lost_motion, inertia, "
    assert caught.value.problems == [
        "wing.ecds.cc16.damper.damping_rate: '1.3e-4 N*m' has the wrong dimension; expected a "
        "damping rate in N*m*s/rad or compatible units, e.g. '1.3e-4 N*m*s/rad'",
        "wing.ecds.cc16.gearbox.colour: unknown key (known keys here: "
        + known
        + "stiffness, mesh_damping, efficiency)",
        "wing.panels[0].mass: missing; expected a mass in kg or compatible units, e.g. '0.185 kg'",
        "wing.panels[0].length: '0.8' has no unit; expected a length in m or compatible "
        "units, e.g. '63 mm'",
        "wing.cables[0]: hinges = [1, 3]: give two adjacent hinge numbers counted from the "
        "root (1), inboard first, e.g. [1, 2]",
        "wing.ground_test.offload[0]: '120 %' must be in [0, 1]; expected a dimensionless "
        "number (a plain number, e.g. 380)",
    ]


def test_cross_key_problems_name_their_keys() -> None:
    text = _wing_text(("90 deg", "0 deg"), ("-180 deg", "0 deg"))
    text = text.replace('ecd = "cc16"', 'ecd = "cc15"', 1)
    text += "[[wing.cables]]\nhinges = [1, 2]\nratio = 1.5\n"
    text += "[wing.ground_test]\ngravity_direction = '-90 deg'\noffload = ['90 %', '0.9', '1']\n"
    text = text.replace(PANEL, "", 1) + PANEL * 0
    with pytest.raises(ConfigError) as caught:
        parse_wing_config(text)
    assert caught.value.problems == [
        "wing.hinges: 2 hinges for 1 panels: give one hinge inboard of each panel, root first",
        "wing.hinges[0].ecd: no ECD 'cc15' in [wing.ecds] (known: ['cc16']; or 'none' for an "
        "undamped hinge)",
        "wing.cables[0].ratio: a rigid cable holds hinge 2's travel (3.14159 rad) at 1.5 x "
        "hinge 1's (1.5708 rad), but they differ, so one of them could never latch (give the "
        "travels in the ratio, or a cable stiffness)",
        "wing.ground_test.offload: 3 values for 1 panels (give one per panel, or one for all)",
    ]


@pytest.mark.parametrize(
    ("change", "expected"),
    [
        (
            ('deployed_angle = "0 deg"', 'deployed_angle = "90 deg"'),
            "wing.hinges[0]: deployed_angle equals stowed_angle (1.5708 rad): no travel",
        ),
        (
            ('end_torque = "1.58 N*m"\n', ""),
            "wing.hinges[0]: missing end_torque; expected a torque in N*m or compatible units, "
            "e.g. '3.73 N*m' (or give spring_table)",
        ),
        (
            (
                'start_torque = "3.73 N*m"\nend_torque = "1.58 N*m"',
                'spring_table = [["0 deg", "3 N*m"], ["45 deg", "2 N*m"]]',
            ),
            "wing.hinges[0]: spring_table ends at 0.785398 rad, before the travel 1.5708 rad",
        ),
        (
            ('ecd = "cc16"', 'ecd = "cc16"\nlatch = { damping = "1 N*m*s/rad" }'),
            "wing.hinges[0].latch: damping needs stiffness (a compliant latch's N*m/rad)",
        ),
        (
            (
                'ecd = "cc16"',
                'ecd = "cc16"\nlatch = { restitution = 0.3, stiffness = "1e3 N*m/rad" }',
            ),
            "wing.hinges[0].latch: give restitution (a rigid latch) or stiffness and damping (a "
            "compliant latch), not both",
        ),
        (
            ("[wing.ecds.cc16.gearbox]", "[wing.ecds.cc17]\n[wing.ecds.cc16.gearbox]"),
            "wing.ecds.cc17: missing damper: an ECD is a [damper] and a [gearbox] section (every "
            "key they take in a single-hinge file), or catalogue = { file, damper, gearbox, "
            "ratio }",
        ),
    ],
)
def test_section_rules(change: tuple[str, str], expected: str) -> None:
    text = _wing_text(("90 deg", "0 deg")).replace(*change)
    with pytest.raises(ConfigError) as caught:
        parse_wing_config(text)
    assert caught.value.problems == [expected]


def test_describe_wing_field_walks_lists_and_named_ecds() -> None:
    expected, known = describe_wing_field(("wing", "ecds", "cc16", "damper", "damping_rate"))
    assert expected is not None
    assert "N*m*s/rad" in expected
    _, known = describe_wing_field(("wing", "hinges", 2, "latch", "colour"))
    assert known == ["restitution", "stiffness", "damping"]
    _, known = describe_wing_field(("wing", "cables", 0))
    assert known == ["hinges", "ratio", "stiffness", "pretension", "pulley_radius"]


def test_single_hinge_commands_refuse_a_wing_file_in_one_line() -> None:
    # (deploy, report, sweep and montecarlo take a wing file: tests/test_wing_studies.py,
    # tests/test_report_wing.py.)
    result = CliRunner().invoke(app, ["repeat", str(EXAMPLE), "-n", "3", "--cool-down", "60 s"])
    assert result.exit_code == 2
    assert result.stderr.strip().splitlines() == [
        f"error: {EXAMPLE}: wing: this is a wing file (docs/wing.md); `ecdsim deploy`, "
        "`report`, `sweep` and `montecarlo` take it, this command takes a single hinge's file"
    ]
