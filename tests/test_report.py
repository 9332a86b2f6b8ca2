"""``ecdsim report``: one self-contained HTML file whose numbers are those of ``deploy --json``."""

from __future__ import annotations

import hashlib
import json
import re
import shutil
from html.parser import HTMLParser
from pathlib import Path
from typing import Any

import pytest
from typer.testing import CliRunner

from ecdsim.cli.app import app
from ecdsim.report.builder import DATA_ELEMENT_ID, lookup
from tests import hand
from tests.conftest import PAPER_CONFIG, ROOT, SavedFigures

runner = CliRunner()
DYNAMIC_CONFIG = ROOT / "examples" / "paper_cc16_dynamic.toml"
SIZING_CONFIG = ROOT / "examples" / "sizing.toml"
TOLERANCE_CONFIG = ROOT / "examples" / "paper_cc16_tolerances.toml"
# Table cells show 6 significant digits: rounding is at most half a unit in the 6th digit.
CELL_REL = 5.1e-6


class _Cells(HTMLParser):
    """Collects <td data-case data-key> texts, the JSON data block and external references."""

    def __init__(self) -> None:
        super().__init__()
        self.cells: dict[tuple[int, str], list[str]] = {}
        self.data: str | None = None
        self.refs: list[str] = []
        self._cell: tuple[int, str] | None = None
        self._in_data = False

    def handle_starttag(self, tag: str, attrs: list[tuple[str, str | None]]) -> None:
        a = dict(attrs)
        for name in ("src", "href"):
            if a.get(name):
                self.refs.append(str(a[name]))
        if tag == "td" and a.get("data-key") is not None:
            self._cell = (int(str(a["data-case"])), str(a["data-key"]))
            self.cells.setdefault(self._cell, [])
        if tag == "script" and a.get("id") == DATA_ELEMENT_ID:
            self._in_data = True

    def handle_endtag(self, tag: str) -> None:
        if tag == "td":
            self._cell = None
        if tag == "script":
            self._in_data = False

    def handle_data(self, data: str) -> None:
        if self._cell is not None:
            self.cells[self._cell].append(data.strip())
        if self._in_data:
            self.data = (self.data or "") + data


def _data_block(html: str) -> str:
    """The report's machine-readable JSON block."""
    parser = _Cells()
    parser.feed(html)
    assert parser.data is not None
    return parser.data


def _report(config: Path, out: Path, *extra: str) -> _Cells:
    result = runner.invoke(app, ["report", str(config), "-o", str(out), *extra])
    assert result.exit_code == 0, result.output
    parser = _Cells()
    parser.feed(out.read_text(encoding="utf-8"))
    return parser


def _deploy_json(config: Path) -> dict[str, Any]:
    result = runner.invoke(app, ["deploy", str(config), "--json"])
    assert result.exit_code == 0, result.output
    document: dict[str, Any] = json.loads(result.stdout)
    return document


@pytest.mark.parametrize("config", [PAPER_CONFIG, DYNAMIC_CONFIG], ids=["paper", "dynamic"])
def test_report_numbers_equal_deploy_json(config: Path, tmp_path: Path) -> None:
    parsed = _report(config, tmp_path / "report.html")
    expected = _deploy_json(config)
    assert parsed.data is not None
    data = json.loads(parsed.data)
    # The machine-readable block is the deploy document itself: equal, not just close.
    assert data["prediction"] == expected
    # The visible cells: every deployment and component cell shows its JSON number.
    keys = {key for _, key in parsed.cells}
    for method in expected["methods"]:
        assert f"{method}.deployment_time_s" in keys
    assert "components.lubrication_friction_Nm" in keys
    assert "system_friction_Nm" in keys
    for (i, key), texts in parsed.cells.items():
        value = lookup(expected["cases"][i], key)
        assert float("".join(texts)) == pytest.approx(value, rel=CELL_REL), (i, key)


def test_visible_cells_are_the_papers_quantities(tmp_path: Path) -> None:
    # Independent of the code: the paper's Eq. 1-4 and 6-7 by hand (tests/hand.py).
    parsed = _report(PAPER_CONFIG, tmp_path / "report.html")
    temps = [-40.0, 25.0, 100.0]
    for i, t in enumerate(temps):
        cell = {key: float("".join(v)) for (j, key), v in parsed.cells.items() if j == i}
        assert cell["damping_rate_Nms_per_rad"] == pytest.approx(hand.becd(t), rel=CELL_REL)
        assert cell["friction_Nm"] == pytest.approx(hand.fecd(t), rel=CELL_REL)
        assert cell["system_friction_Nm"] == pytest.approx(hand.fs(t), rel=CELL_REL)
        assert cell["paper.deployment_time_s"] == pytest.approx(hand.paper_time(t), rel=CELL_REL)
        assert cell["exact.deployment_time_s"] == pytest.approx(hand.exact_time(t), rel=CELL_REL)
    # BG = 0.26 BD at the damper shaft, at 25 degC BD = 1.3e-4 (paper section 6).
    bg = float("".join(parsed.cells[(1, "components.gearbox_damping_rate_Nms_per_rad")]))
    assert bg == pytest.approx(0.26 * 1.3e-4, rel=CELL_REL)


def test_report_is_self_contained_with_provenance(
    tmp_path: Path, saved_figures: SavedFigures
) -> None:
    out = tmp_path / "report.html"
    parsed = _report(PAPER_CONFIG, out)
    # The three inline figures, as drawn: what each shows, in which units.
    shown = [
        (" ".join(axes.get_title().split()), axes.get_xlabel(), axes.get_ylabel())
        for figure in saved_figures.figures.values()
        for axes in figure.axes
    ]
    system = "CDA Cc-16 test deployment (paper section 6)"
    assert shown == [
        (f"{system}: angle against time", "time since release [s]", "deployed angle [deg]"),
        (f"{system}: speed against time", "time since release [s]", "input shaft speed [rad/s]"),
        (
            f"{system}: ECD torque against speed",
            "input shaft speed [rad/s]",
            "ECD reaction torque [N*m]",
        ),
    ]
    html = out.read_text(encoding="utf-8")
    # Nothing to fetch: every src/href is inline data or an in-page anchor.
    assert parsed.refs, "the report should contain inline figures"
    assert all(r.startswith(("data:", "#")) for r in parsed.refs), parsed.refs
    assert len([r for r in parsed.refs if r.startswith("data:image/png;base64,")]) == 3
    assert hashlib.sha256(PAPER_CONFIG.read_bytes()).hexdigest() in html
    data = json.loads(parsed.data or "{}")
    assert (
        data["provenance"]["config_sha256"] == hashlib.sha256(PAPER_CONFIG.read_bytes()).hexdigest()
    )
    assert re.search(r"\d{4}-\d\d-\d\d \d\d:\d\d:\d\d UTC", html)
    # Input summary with units: the spring's start torque in N*m, the travel in rad (a
    # key may break after its dot on a phone: <wbr>, tests/test_report_layout.py).
    assert re.search(r"load\.<wbr>start_torque</code></td><td[^>]*>3\.73</td><td>N\*m</td>", html)
    assert re.search(r"load\.<wbr>travel</code></td><td[^>]*>1\.57</td><td>rad</td>", html)


def test_report_shows_margins_when_requirements_are_configured(tmp_path: Path) -> None:
    out = tmp_path / "report.html"
    parsed = _report(SIZING_CONFIG, out)
    data = json.loads(parsed.data or "{}")
    margins = data["margins"]
    names = [c["name"] for c in margins["checks"]]
    assert names == [
        "min_deployment_time",
        "max_deployment_time",
        "max_end_speed",
        "max_input_torque",
        "no_stall",
        "min_torque_margin",
    ]
    # The time checks read the exact deployment times of the prediction at the same
    # temperatures (-40, 25, 100 degC), and "min time 10 s" margin is (t - 10) / t.
    times = [hand.exact_time(t) for t in (-40.0, 25.0, 100.0)]
    check = margins["checks"][0]
    assert check["values"] == pytest.approx(times, rel=1e-12)  # same floating-point path
    assert check["margins"] == pytest.approx([(t - 10.0) / t for t in times], rel=1e-12)
    assert 'id="margins"' in out.read_text(encoding="utf-8")


def test_report_summarises_montecarlo_when_tolerances_are_configured(tmp_path: Path) -> None:
    import json as json_module

    from ecdsim.config import load_config
    from ecdsim.montecarlo import InProcess, build_plan, run
    from ecdsim.montecarlo.stats import summarize
    from ecdsim.report.builder import DATA_ELEMENT_ID, REPORT_MC_SAMPLES, REPORT_MC_SEED

    out = tmp_path / "report.html"
    _report(TOLERANCE_CONFIG, out)
    html = out.read_text(encoding="utf-8")
    assert 'id="montecarlo"' in html
    assert "damper.damping_rate" in html
    # The report's study equals an independent run of the same plan by the Monte Carlo
    # library (same seed, same samples): identical percentiles, bit for bit.
    config = load_config(TOLERANCE_CONFIG)
    seed = None if config.spec.tolerances and config.spec.tolerances.seed is not None else 0
    assert seed in (None, REPORT_MC_SEED)
    study = tmp_path / "study"
    plan = build_plan(config, REPORT_MC_SAMPLES, "exact", seed=seed, out=study)
    run(plan, study, InProcess())
    reference = summarize(plan, study)
    start = html.index(f'id="{DATA_ELEMENT_ID}">') + len(f'id="{DATA_ELEMENT_ID}">')
    data = json_module.loads(html[start : html.index("</script>", start)].replace("<\\/", "</"))
    ours = data["montecarlo"]["cases"]
    for mine, theirs in zip(ours, reference["cases"], strict=True):
        assert (
            mine["deployment_time_s"]["percentiles"] == theirs["deployment_time_s"]["percentiles"]
        )
        p50 = theirs["deployment_time_s"]["percentiles"]["P50"]["value"]
        assert f"{p50:.6g}" in html  # the visible table shows the same P50


def test_report_lists_warnings(tmp_path: Path) -> None:
    # At 150 degC the paper's FS_T = 0.58 - 0.0044 * 150 = -0.08 N*m < 0 (a warning; BD_T
    # = BD (1 - 0.004 * 125) is still positive, so the case is solved, not an error).
    out = tmp_path / "report.html"
    _report(PAPER_CONFIG, out, "-T", "150")
    html = out.read_text(encoding="utf-8")
    assert 'data-code="negative_friction"' in html
    assert html.count('data-code="negative_friction"') == 1  # one case, one warning
    data = json.loads(_data_block(html))
    assert [w["code"] for w in data["prediction"]["warnings"]] == ["negative_friction"]
    assert data["prediction"]["cases"][0]["system_friction_Nm"] == pytest.approx(
        0.58 - 0.0044 * 150.0, rel=1e-12
    )  # by hand: one multiply-add


def test_report_bad_config_exits_2(tmp_path: Path) -> None:
    bad = tmp_path / "bad.toml"
    bad.write_text(PAPER_CONFIG.read_text().replace('"1.57 rad"', '"1.57 N*m"'))
    result = runner.invoke(app, ["report", str(bad), "-o", str(tmp_path / "r.html")])
    assert result.exit_code == 2
    assert "load.travel" in result.output
    assert not (tmp_path / "r.html").exists()


def test_pdf_without_browser_is_a_clear_error(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    monkeypatch.setenv("PATH", str(tmp_path / "empty"))
    monkeypatch.setenv("ECDSIM_CHROMIUM", str(tmp_path / "no-such-browser"))
    out = tmp_path / "report.html"
    result = runner.invoke(app, ["report", str(PAPER_CONFIG), "-o", str(out), "--pdf"])
    assert result.exit_code == 2
    assert "--pdf needs a Chromium browser" in result.output
    assert out.exists()  # the HTML was written before the PDF step


def test_pdf_with_chromium(tmp_path: Path) -> None:
    if shutil.which("chromium") is None:
        pytest.fail("chromium is not installed (make test installs it: apt-get install chromium)")
    out = tmp_path / "report.html"
    result = runner.invoke(app, ["report", str(PAPER_CONFIG), "-o", str(out), "--pdf"])
    assert result.exit_code == 0, result.output
    pdf = (tmp_path / "report.pdf").read_bytes()
    assert pdf.startswith(b"%PDF-")
    assert len(pdf) > 20_000  # three inline figures cannot fit in less
