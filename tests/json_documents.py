"""The ``--json`` documents of every command, produced from the examples and variants of
them that reach each optional part (stalls and warnings, ground tests, two-node heating,
a compliant mesh, bad rows, one temperature, torque margins).

tests/test_json_schemas.py validates each against its shipped schema
(``src/ecdsim/schemas/``); ``scripts/json_schemas.py`` drafts the schemas from the same
documents. One list, so that what is drafted is what is checked.
"""

from __future__ import annotations

import json
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from typer.testing import CliRunner

from ecdsim.cli.app import app

ROOT = Path(__file__).resolve().parent.parent
EXAMPLES = ROOT / "examples"


@dataclass(frozen=True)
class Case:
    """One command whose stdout is a JSON document of ``schema``.

    ``argv`` builds the command line in a scratch folder (where variant files go).
    """

    name: str
    schema: str
    argv: Callable[[Path], list[str]]


def _variant(folder: Path, source: str, name: str, edits: list[tuple[str, str]]) -> str:
    text = (EXAMPLES / source).read_text(encoding="utf-8")
    for old, new in edits:
        assert old in text, old
        text = text.replace(old, new)
    path = folder / name
    path.write_text(text, encoding="utf-8")
    return str(path)


def _stalling(folder: Path) -> list[str]:
    path = _variant(
        folder,
        "paper_cc16.toml",
        "stall.toml",
        [
            ('end_torque = "1.58 N*m"', 'end_torque = "1.2 N*m"'),
            ("[gearbox]", 'max_linear_speed = "60 rad/s"\n\n[gearbox]'),
        ],
    )
    return ["deploy", path, "-T", "-40", "-T", "100", "--json"]


TWO_NODE = (
    "[gearbox]",
    '[damper.thermal]\nheat_capacity = "0.002 J/K"\nthermal_resistance = "40 K/W"\n'
    'housing_heat_capacity = "0.2 J/K"\nhousing_thermal_resistance = "200 K/W"\n\n[gearbox]',
)


def _two_node(folder: Path) -> str:
    return _variant(folder, "paper_cc16_dynamic.toml", "two_node.toml", [TWO_NODE])


def _compliant(folder: Path) -> list[str]:
    path = _variant(
        folder,
        "paper_cc16_dynamic.toml",
        "compliant.toml",
        [
            (
                'lost_motion = "0 deg"',
                'lost_motion = "0.25 deg"\nstiffness = "2 kN*m/rad"\n'
                'mesh_damping = "500 mN*m*s/rad"',
            )
        ],
    )
    return ["deploy", path, "-T", "25", "-m", "dynamic", "--json"]


def _bad_rows(folder: Path) -> list[str]:
    text = (EXAMPLES / "drop_test.csv").read_text(encoding="utf-8")
    path = folder / "bad_rows.csv"
    path.write_text(text + "25,-5,50,180,10,0.02,0.005\n25,abc,50,180,10,0.02,0.005\n", "utf-8")
    return ["fit", "drop-test", str(path), "--json"]


def _one_temperature(folder: Path) -> list[str]:
    lines = (EXAMPLES / "drop_test.csv").read_text(encoding="utf-8").splitlines()
    path = folder / "one_temperature.csv"
    path.write_text("\n".join([lines[0], *(x for x in lines[1:] if x.startswith("25,"))]) + "\n")
    return ["fit", "drop-test", str(path), "--json"]


def _montecarlo(folder: Path, margin: bool = False) -> list[str]:
    config = str(EXAMPLES / "paper_cc16_tolerances.toml")
    if margin:
        text = (EXAMPLES / "paper_cc16_tolerances.toml").read_text(encoding="utf-8")
        text += (
            '\n[requirements]\ntemperature_range = ["-40 degC", "100 degC"]\n'
            'min_deployment_time = "10 s"\nmax_deployment_time = "60 s"\n'
            'max_end_speed = "0.1 rad/s"\n'
            "min_torque_margin = 0.5\n[requirements.torque_margin]\n"
            'damping_speed = "0.005 rad/s"\nfactors = { friction = 1.2 }\n'
        )
        config = str(folder / "margin.toml")
        Path(config).write_text(text, encoding="utf-8")
    out = folder / ("mc-margin" if margin else "mc")
    return ["montecarlo", config, "--samples", "400", "--out", str(out), "--no-plot", "--json"]


def _repeat(config: str | Callable[[Path], str]) -> Callable[[Path], list[str]]:
    def argv(folder: Path) -> list[str]:
        path = config(folder) if callable(config) else config
        return ["repeat", path, "--count", "3", "--cool-down", "60 s", "--stow-time", "30 s",
                "-T", "25", "--json"]  # fmt: skip

    return argv


def _placeholder(folder: Path) -> list[str]:
    """deploy on the file fit drop-test -o writes without --config: a placeholder load."""
    fitted = folder / "fitted.toml"
    result = CliRunner().invoke(app, ["fit", "drop-test", DROP, "-o", str(fitted)])
    assert result.exit_code == 0, result.output
    return ["deploy", str(fitted), "--json"]


WING = str(EXAMPLES / "wing_cc16_three_panel.toml")


# The outer hinge's spring in the example wing, to the end of its end torque.
OUTER_END = (
    'name = "outer"\nstowed_angle = "180 deg"\ndeployed_angle = "0 deg"\n'
    'start_torque = "3.73 N*m"                          # ILLUSTRATIVE, over 180 deg\n'
    'end_torque = "1.58 N*m"'
)


def _wing_variant(folder: Path) -> list[str]:
    """The example wing with a heated damper at every hinge, a compliant root latch and an
    outer spring too weak to latch: the optional parts (peak temperatures, a latch's peak
    torque, a stuck hinge)."""
    path = _variant(
        folder,
        "wing_cc16_three_panel.toml",
        "wing_variant.toml",
        [
            (
                "[wing.ecds.cc16.gearbox]",
                '[wing.ecds.cc16.damper.thermal]\nheat_capacity = "0.002 J/K"\n'
                'thermal_resistance = "40 K/W"\n\n[wing.ecds.cc16.gearbox]',
            ),
            (
                "latch = { restitution = 0.0 }                      # ILLUSTRATIVE: a rigid latch",
                'latch = { stiffness = "200 N*m/rad", damping = "0.5 N*m*s/rad" }',
            ),
            (OUTER_END, OUTER_END.replace('"1.58 N*m"', '"0.2 N*m"')),
        ],
    )
    return ["deploy", path, "-T", "25", "--json"]


PAPER = str(EXAMPLES / "paper_cc16.toml")
DYNAMIC = str(EXAMPLES / "paper_cc16_dynamic.toml")
DROP = str(EXAMPLES / "drop_test.csv")
SIZING = str(EXAMPLES / "sizing.toml")
BUDGET = str(EXAMPLES / "torque_budget.toml")
CONFIG_BUDGET = str(EXAMPLES / "paper_cc16_budget.toml")
CATALOGUE = str(EXAMPLES / "catalogue.toml")

CASES: tuple[Case, ...] = (
    Case("deploy paper", "deploy", lambda _: ["deploy", PAPER, "--json"]),
    Case(
        "deploy exact only, us",
        "deploy",
        lambda _: ["deploy", PAPER, "-m", "exact", "--units", "us", "--json"],
    ),  # noqa: E501
    Case("deploy dynamic", "deploy", lambda _: ["deploy", DYNAMIC, "--json"]),
    Case(
        "deploy ground test",
        "deploy",
        lambda _: ["deploy", str(EXAMPLES / "paper_cc16_ground_test.toml"), "--json"],
    ),  # noqa: E501
    Case("deploy stall and warnings", "deploy", _stalling),
    Case(
        "deploy two-node heating",
        "deploy",
        lambda f: ["deploy", _two_node(f), "-T", "25", "-m", "dynamic", "--json"],
    ),  # noqa: E501
    Case("deploy compliant mesh", "deploy", _compliant),
    Case("deploy placeholder load", "deploy", _placeholder),
    Case("fit drop-test", "fit_drop_test", lambda _: ["fit", "drop-test", DROP, "--json"]),
    Case(
        "fit drop-test timing noise",
        "fit_drop_test",
        lambda _: ["fit", "drop-test", DROP, "--noise", "timing", "--json"],
    ),  # noqa: E501
    Case("fit drop-test bad rows", "fit_drop_test", _bad_rows),
    Case("fit drop-test one temperature", "fit_drop_test", _one_temperature),
    Case(
        "fit trace",
        "fit_trace",
        lambda _: [
            "fit",
            "trace",
            str(EXAMPLES / "deployment_trace.csv"),
            "--config",
            PAPER,
            "--json",
        ],
    ),  # noqa: E501
    Case(
        "fit trace spring",
        "fit_trace",
        lambda _: [
            "fit",
            "trace",
            str(EXAMPLES / "deployment_trace.csv"),
            "--config",
            PAPER,
            "--fit-spring",
            "--json",
        ],
    ),  # noqa: E501
    Case("size", "size", lambda _: ["size", SIZING, "--catalog", CATALOGUE, "--json"]),
    Case(
        "size one pair",
        "size",
        lambda _: [
            "size",
            SIZING,
            "--catalog",
            CATALOGUE,
            "--damper",
            "CDA Cc-16 damper",
            "--gearbox",
            "CDA Cc-16 gearbox",
            "--json",
        ],
    ),  # noqa: E501
    Case(
        "compare-fluid",
        "compare_fluid",
        lambda _: ["compare-fluid", str(EXAMPLES / "fluid.toml"), "--json"],
    ),  # noqa: E501
    Case(
        "compare-fluid measured power law",
        "compare_fluid",
        lambda _: ["compare-fluid", str(EXAMPLES / "fluid_measured.toml"), "--json"],
    ),
    Case("montecarlo", "montecarlo", _montecarlo),
    Case("montecarlo torque margin", "montecarlo", lambda f: _montecarlo(f, margin=True)),
    Case("repeat", "repeat", _repeat(DYNAMIC)),
    Case("repeat two-node", "repeat", _repeat(_two_node)),
    # The qualification commands (docs/qualification.md).
    Case("margin budget file", "margin", lambda _: ["margin", BUDGET, "--json"]),
    Case("margin config budget", "margin", lambda _: ["margin", CONFIG_BUDGET, "--json"]),
    Case("margin sizing config", "margin", lambda _: ["margin", SIZING, "-T", "25", "--json"]),
    Case(
        "margin ground test",
        "margin",
        lambda _: ["margin", str(EXAMPLES / "paper_cc16_ground_test.toml"), "--json"],
    ),
    Case(
        "reliability demonstrated",
        "reliability_demonstrated",
        lambda _: ["reliability", "demonstrated", "--runs", "59", "--failures", "1", "--json"],
    ),
    Case(
        "reliability runs-needed",
        "reliability_runs_needed",
        lambda _: ["reliability", "runs-needed", "--target", "0.99", "--json"],
    ),
    Case(
        "reliability weibull",
        "reliability_weibull",
        lambda _: [
            "reliability",
            "weibull",
            str(EXAMPLES / "life_test.csv"),
            "--at",
            "1000",
            "--json",
        ],
    ),  # fmt: skip
    Case(
        "fit drive-test",
        "fit_drive_test",
        lambda f: [
            "fit",
            "drive-test",
            str(EXAMPLES / "drive_test.csv"),
            "--json",
            "-o",
            str(f / "hinge.toml"),
            "--config",
            CONFIG_BUDGET,
        ],
    ),  # fmt: skip
    Case(
        "fit fluid-damper",
        "fit_fluid_damper",
        lambda _: ["fit", "fluid-damper", str(EXAMPLES / "fluid_bench.csv"), "--json"],
    ),
    Case(
        "sweep",
        "sweep",
        lambda _: [
            "sweep",
            PAPER,
            "--vary",
            "gearbox.ratio=300,380",
            "--vary",
            "load.start_torque=3.2,3.73 N*m",
            "-T",
            "25",
            "--json",
        ],
    ),  # noqa: E501
    Case(
        "sweep dynamic",
        "sweep",
        lambda _: ["sweep", DYNAMIC, "--vary", "load.inertia=1,5", "-T", "25", "--json"],
    ),  # noqa: E501
    # A wing file's documents (docs/wing.md): its deploy and Monte Carlo have their own
    # schemas, its sweep is a sweep document (per-hinge columns hinge_J_...).
    Case("wing deploy", "wing_deploy", lambda _: ["deploy", WING, "--json"]),
    Case("wing deploy heated, compliant latch, stuck", "wing_deploy", _wing_variant),
    Case(
        "wing montecarlo",
        "wing_montecarlo",
        lambda f: [
            "montecarlo",
            WING,
            "--samples",
            "40",
            "-T",
            "25",
            "--out",
            str(f / "wing-mc"),
            "--no-plot",
            "--json",
        ],
    ),
    Case(
        "wing sweep",
        "sweep",
        lambda _: ["sweep", WING, "--vary", "wing.panels[2].mass=0.9,1.1 kg", "-T", "25", "--json"],
    ),
)


def document(case: Case, folder: Path) -> Any:
    """Run the case's command in process; its stdout parsed (AssertionError on failure)."""
    folder.mkdir(parents=True, exist_ok=True)
    result = CliRunner().invoke(app, case.argv(folder))
    assert result.exit_code == 0, f"{case.name}: exit {result.exit_code}\n{result.output}"
    return json.loads(result.stdout)
