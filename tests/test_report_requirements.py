"""The report's requirements section, findings sentence and solver appendix (issue 14, item 9).

Expected numbers are the paper's section 6 example by hand (tests/hand.py): exact
deployment times, the friction laws and the torque margin TM = Te / (FECD + FS + BECD w)
- 1 at the end of travel (docs/sizing.md section 5).
"""

from __future__ import annotations

from html import unescape
from html.parser import HTMLParser
from pathlib import Path

from typer.testing import CliRunner

from ecdsim.cli.app import app
from tests import hand
from tests.conftest import PAPER_CONFIG, ROOT

runner = CliRunner()
SIZING = ROOT / "examples" / "sizing.toml"
DYNAMIC = ROOT / "examples" / "paper_cc16_dynamic.toml"
TEMPS = (-40.0, 25.0, 100.0)


class _Table(HTMLParser):
    """The text of each row of the table with a given id, cells in order."""

    def __init__(self, table_id: str) -> None:
        super().__init__()
        self.table_id = table_id
        self.rows: list[list[str]] = []
        self.attrs: list[dict[str, str | None]] = []
        self._inside = False
        self._cell: list[str] | None = None

    def handle_starttag(self, tag: str, attrs: list[tuple[str, str | None]]) -> None:
        a = dict(attrs)
        if tag == "table":
            self._inside = a.get("id") == self.table_id
        if self._inside and tag == "tr":
            self.rows.append([])
            self.attrs.append(a)
        if self._inside and tag in {"td", "th"}:
            self._cell = []

    def handle_endtag(self, tag: str) -> None:
        if tag == "table":
            self._inside = False
        if self._inside and tag in {"td", "th"} and self._cell is not None:
            self.rows[-1].append(" ".join("".join(self._cell).split()))
            self._cell = None

    def handle_data(self, data: str) -> None:
        if self._cell is not None:
            self._cell.append(data)


def table(html: str, table_id: str) -> _Table:
    parsed = _Table(table_id)
    parsed.feed(html)
    return parsed


def report(config: Path, tmp_path: Path, name: str = "report.html") -> str:
    out = tmp_path / name
    result = runner.invoke(app, ["report", str(config), "-o", str(out)])
    assert result.exit_code == 0, result.output
    return out.read_text(encoding="utf-8")


def requirement_rows(html: str) -> dict[tuple[str, int], list[str]]:
    """(check name, temperature index) -> [T, value, limit, result, margin]."""
    parsed = table(html, "margins")
    rows = {}
    for cells, attrs in zip(parsed.rows, parsed.attrs, strict=True):
        if attrs.get("data-check") is None:
            continue
        key = (str(attrs["data-check"]), int(str(attrs["data-row"])))
        rows[key] = cells[-5:]  # the requirement's name spans its rows (first row only)
    return rows


def test_each_requirement_at_each_temperature_with_value_limit_result_margin(
    tmp_path: Path,
) -> None:
    html = report(SIZING, tmp_path)
    assert '<h2 id="requirements">Requirements</h2>' in html
    header = table(html, "margins").rows[0]
    assert header == ["requirement", "T [degC]", "value", "limit", "result", "margin"]
    rows = requirement_rows(html)
    for i, t in enumerate(TEMPS):
        time = hand.exact_time(t)
        # 6 significant digits; margins 1 - t_min / t and t_max / t - 1 to 0.1 %.
        assert rows[("min_deployment_time", i)] == [
            f"{t:g}",
            f"{time:.6g} s",
            ">= 10 s",
            "pass",
            f"{100 * (1 - 10 / time):+.1f} %",
        ]
        assert rows[("max_deployment_time", i)][2:] == [
            "<= 60 s",
            "pass",
            f"{100 * (60 / time - 1):+.1f} %",
        ]
        # The torque margin at the end of travel with the damping at 0.005 rad/s.
        friction = hand.fecd(t) + hand.fs(t) + hand.becd(t) * 0.005
        tm = hand.TE / friction - 1.0
        assert rows[("min_torque_margin", i)][1:] == [
            f"{tm:.4g}",
            ">= 0",
            "pass",
            f"{100 * tm:+.1f} %",
        ]
        # No stall: Te - (FECD + FS) > 0, the margin relative to the friction.
        net = hand.TE - hand.fecd(t) - hand.fs(t)
        assert rows[("no_stall", i)][1:3] == [f"{net:.6g} N*m", "> 0 N*m"]
    words = " ".join(unescape(html).split())
    assert "deployment time <= 60 s: t_max / t - 1" in words
    assert "every requirement met at every temperature" in words


def test_a_missed_requirement_fails_at_its_temperature_only(tmp_path: Path) -> None:
    config = tmp_path / "strict.toml"
    text = SIZING.read_text(encoding="utf-8")
    config.write_text(text.replace('max_deployment_time = "60 s"', 'max_deployment_time = "40 s"'))
    html = report(config, tmp_path)
    rows = requirement_rows(html)
    time = hand.exact_time(-40.0)  # 48.13 s > 40 s: 40 / 48.13 - 1 = -16.9 %
    assert rows[("max_deployment_time", 0)][2:] == [
        "<= 40 s",
        "FAIL",
        f"{100 * (40 / time - 1):+.1f} %",
    ]
    assert rows[("max_deployment_time", 1)][3] == "pass"  # 26.86 s at 25 degC
    assert "at least one requirement not met" in html


def test_no_requirements_no_section_and_findings_only_as_checked(tmp_path: Path) -> None:
    html = report(PAPER_CONFIG, tmp_path)
    assert 'id="requirements"' not in html
    assert 'id="margins"' not in html
    words = " ".join(unescape(html).split())
    # No linear-range limit in the paper's config: nothing claims it was checked.
    assert "No warning: checked for stall, at every temperature and by every method." in words
    assert "None:" not in words  # (issue 26 item 6: the section began "None:")
    assert "checked for stall and" not in words
    assert "The damper's linear range is not checked" in words
    # With limits (far above this deployment's shaft speed 0.0837 * 380 = 31.8 rad/s):
    limited = tmp_path / "limited.toml"
    text = PAPER_CONFIG.read_text(encoding="utf-8")
    limited.write_text(
        text.replace("[gearbox]", 'max_linear_speed = "3000 rad/s"\n\n[gearbox]', 1),
        encoding="utf-8",
    )
    words = " ".join(unescape(report(limited, tmp_path, "limited.html")).split())
    assert "No warning: checked for stall and the damper's linear range, at every" in words
    assert "not checked" not in words


def test_solver_internals_are_in_the_appendix(tmp_path: Path) -> None:
    html = report(DYNAMIC, tmp_path)
    inputs = [row[0] for row in table(html, "inputs").rows[1:]]
    assert "analysis.rtol" not in inputs
    assert "analysis.integrator" not in inputs
    assert "load.inertia" in inputs
    appendix = html.index('<h2 id="appendix">')
    assert appendix > html.index('id="inputs"')  # after the inputs: last
    settings = {row[0]: row[1] for row in table(html, "solver-settings").rows}
    assert settings["integrator"] == "RODAS4"
    assert settings["rtol"] == "1e-08"
    dynamic = table(html, "solver-dynamic").rows
    assert dynamic[0] == [
        "T [degC]",
        "status",
        "energy balance error [-]",
        "closed-form segments",
        "integrated segments",
        "integrator steps",
    ]
    # A linear damper without heating: one closed-form segment from release to the
    # latch (no stick, no impact), nothing integrated.
    assert [row[:2] + row[3:] for row in dynamic[1:]] == [
        [f"{t:g}", "latched", "1", "0", "0"] for t in TEMPS
    ]


def test_a_heated_damper_is_integrated_and_its_steps_counted(tmp_path: Path) -> None:
    config = tmp_path / "heated.toml"
    text = DYNAMIC.read_text(encoding="utf-8")
    config.write_text(
        text.replace("[gearbox]", '[damper.thermal]\nheat_capacity = "0.5 mJ/K"\n\n[gearbox]', 1)
    )
    html = report(config, tmp_path)
    for row in table(html, "solver-dynamic").rows[1:]:
        temperature, status, _, closed, integrated, steps = row
        assert status == "latched"
        # Self-heating makes the damping law nonlinear in time: integrated, by RODAS4.
        assert (closed, integrated) == ("0", "1")
        assert steps.isdigit()
        assert int(steps) > 10
