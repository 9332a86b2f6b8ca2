"""The HTML report on a phone (390 px wide) and a desktop (1280 px), in headless Chromium.

One report holds every table the report can have (the ground-test example with
[requirements], [tolerances] and [budget] added). On a phone the page itself never
scrolls sideways: a table wider than the screen scrolls inside its own box, which takes
the keyboard focus and is named for a screen reader, and the inputs table wraps into the
width (keys broken after a dot, numbers whole). The desktop layout keeps each input key
on one line. axe-core finds no violation at either width. Each state is screenshotted
into ``$ECDSIM_SHOTS`` (default: a folder in the system's temporary directory), to look
at. Without /usr/bin/chromium or axe-core the tests fail naming what to install.
"""

from __future__ import annotations

import os
import re
import tempfile
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import pytest
from typer.testing import CliRunner

from ecdsim.cli.app import app
from tests.conftest import ROOT

CHROMIUM = Path("/usr/bin/chromium")
AXE = Path(os.environ.get("ECDSIM_AXE", str(ROOT / ".venv/axe/node_modules/axe-core/axe.min.js")))
SHOTS = Path(os.environ.get("ECDSIM_SHOTS", str(Path(tempfile.gettempdir()) / "ecdsim-report")))
EXAMPLES = ROOT / "examples"
# Every table of the report (the budget's once per phase).
TABLES = [
    "provenance",
    "deployment",
    "ground-test",
    "dynamic-end",
    "dynamic-damper",
    "components",
    "margins",
    "torque-margin",
    "montecarlo",
    "tolerances",
    "budget",
    "budget",
    "requirement-misses",
    "inputs",
    "solver-settings",
    "solver-dynamic",
]


def _section(path: Path, header: str) -> str:
    """The file from the line ``header`` to its end (its study sections)."""
    text = path.read_text(encoding="utf-8")
    return text[text.index("\n" + header + "\n") + 1 :]


@pytest.fixture(scope="module")
def report(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """The ground-test example (dynamic method, gravity, two-node heating) with the
    sizing example's [requirements], the tolerance example's [tolerances] and the budget
    example's [budget]: a report with every table."""
    folder = tmp_path_factory.mktemp("layout")
    budget = _section(EXAMPLES / "paper_cc16_budget.toml", "[budget]")
    # This model has a resistive table and gravity too: each needs a kind in the budget.
    kinds = 'system_friction = "unknown" }'
    assert kinds in budget
    budget = budget.replace(
        kinds, 'system_friction = "unknown", resistive_table = "unknown", gravity = "known" }'
    )
    config = folder / "everything.toml"
    config.write_text(
        "\n".join(
            [
                (EXAMPLES / "paper_cc16_ground_test.toml").read_text(encoding="utf-8"),
                _section(EXAMPLES / "sizing.toml", "[requirements]"),
                _section(EXAMPLES / "paper_cc16_tolerances.toml", "[tolerances]"),
                budget,
            ]
        ),
        encoding="utf-8",
    )
    out = folder / "everything.html"
    result = CliRunner().invoke(app, ["report", str(config), "-o", str(out)])
    assert result.exit_code == 0, result.output
    return out


@pytest.fixture(scope="module")
def browser() -> Iterator[Any]:
    if not CHROMIUM.is_file():
        pytest.fail(f"{CHROMIUM} is missing: apt-get install -y chromium (make test does it)")
    if not AXE.is_file():
        pytest.fail(f"{AXE} is missing: run bash scripts/ensure-axe.sh (npm; make test does it)")
    from playwright.sync_api import sync_playwright

    SHOTS.mkdir(parents=True, exist_ok=True)
    with sync_playwright() as p:
        chromium = p.chromium.launch(
            executable_path=str(CHROMIUM),
            # keyboard scrolling at once, not animated: the test reads where it ends
            args=["--no-sandbox", "--disable-gpu", "--disable-smooth-scrolling"],
            headless=True,
        )
        try:
            yield chromium
        finally:
            chromium.close()


def _open(browser: Any, report: Path, width: int) -> Any:
    """The report in a page ``width`` CSS pixels wide; at 390 as a phone shows it (its
    viewport meta tag applies, as on a phone, rather than a 980 px desktop layout)."""
    phone = width < 600
    context = browser.new_context(
        viewport={"width": width, "height": 900}, is_mobile=phone, has_touch=phone
    )
    page = context.new_page()
    page.goto(report.as_uri())
    return page


def _axe(page: Any) -> None:
    page.add_script_tag(path=str(AXE))
    violations = page.evaluate(
        "async () => (await axe.run(document, {resultTypes: ['violations']})).violations"
    )
    report = [
        f"{v['id']} ({v['impact']}): {v['help']}: "
        + "; ".join(str(n["target"]) for n in v["nodes"][:5])
        for v in violations
    ]
    assert not report, "\n".join(report)


# For each table: its right edge, and the box that scrolls it (if any) with that box's
# right edge, widths, focusability and name.
TABLE_LAYOUT = """() => [...document.querySelectorAll('table')].map(table => {
  const box = table.closest('.scroll');
  const edge = element => element.getBoundingClientRect().right;
  return {
    name: table.id || table.className,
    right: edge(table),
    box: box && {
      right: edge(box),
      scrolls: box.scrollWidth > box.clientWidth,
      overflow: getComputedStyle(box).overflowX,
      tabindex: box.getAttribute('tabindex'),
      role: box.getAttribute('role'),
      label: box.getAttribute('aria-label'),
    },
  };
})"""


@pytest.mark.parametrize("width", [390, 1280])
def test_no_table_widens_the_page(browser: Any, report: Path, width: int) -> None:
    page = _open(browser, report, width)
    try:
        page.screenshot(path=str(SHOTS / f"report-{width}.png"), full_page=True)
        viewport = page.evaluate("document.documentElement.clientWidth")
        assert viewport == width
        # The page itself never scrolls sideways.
        assert page.evaluate("document.documentElement.scrollWidth") == width
        tables = page.evaluate(TABLE_LAYOUT)
        assert [t["name"] for t in tables] == TABLES
        for table in tables:
            if table["name"] == "provenance":  # a narrow layout: the hash wraps
                assert table["box"] is None
                assert table["right"] <= width, table
                continue
            box = table["box"]
            assert box is not None, table  # in a box of its own ...
            assert box["right"] <= width, table  # ... that fits the screen ...
            assert box["overflow"] == "auto", table  # ... and scrolls what does not fit,
            assert box["tabindex"] == "0", table  # by keyboard too,
            assert box["role"] == "region", table  # a named region for a screen reader
            assert box["label"].endswith("(table)"), table
        scrolling = {t["name"] for t in tables if t["box"] and t["box"]["scrolls"]}
        if width == 390:
            # The wide tables scroll in their boxes (the test would hold trivially if none
            # were wider than a phone); the inputs wrap into the width instead.
            assert {"deployment", "components", "montecarlo", "budget"} <= scrolling
            assert "inputs" not in scrolling
        else:
            assert scrolling == set()
        _axe(page)
    finally:
        page.context.close()


def test_a_table_box_scrolls_with_the_keyboard(browser: Any, report: Path) -> None:
    page = _open(browser, report, 390)
    try:
        box = page.locator(".scroll:has(#components)")
        assert box.evaluate("b => b.scrollLeft") == 0
        box.focus()
        page.keyboard.press("ArrowRight")
        moved = box.evaluate("b => b.scrollLeft")
        assert moved > 0  # a column further
        for _ in range(40):
            page.keyboard.press("ArrowRight")
        shown = box.evaluate("b => [b.scrollLeft, b.scrollWidth - b.clientWidth]")
        assert shown[0] == shown[1] > moved  # up to the last column, and no further
        page.screenshot(path=str(SHOTS / "report-390-components-scrolled.png"))
    finally:
        page.context.close()


# Each key cell's and value cell's lines (the client rectangles of their text).
INPUT_LINES = """() => [...document.querySelectorAll('#inputs tbody tr')].map(row => {
  const lines = cell => {
    const range = document.createRange();
    range.selectNodeContents(cell);
    return new Set([...range.getClientRects()].map(r => Math.round(r.top))).size;
  };
  return {key: row.cells[0].textContent, value: row.cells[1].textContent,
          key_lines: lines(row.cells[0]), value_lines: lines(row.cells[1])};
})"""
NUMBER = re.compile(r"-?\d+(\.\d+)?(e[-+]?\d+)?")


def test_the_inputs_wrap_on_a_phone_and_not_on_a_desktop(browser: Any, report: Path) -> None:
    phone = _open(browser, report, 390)
    desk = _open(browser, report, 1280)
    try:
        small = phone.evaluate(INPUT_LINES)
        wide = desk.evaluate(INPUT_LINES)
        assert [r["key"] for r in small] == [r["key"] for r in wide]
        keys = {r["key"]: r for r in small}
        # the dotted keys as the config writes them (the break points are not characters)
        assert "damper.thermal.housing_thermal_resistance" in keys
        assert keys["damper.thermal.housing_thermal_resistance"]["key_lines"] > 1
        numbers = [r for r in small if NUMBER.fullmatch(r["value"])]
        assert len(numbers) > 30
        for row in numbers:  # a number is never broken across lines
            assert row["value_lines"] == 1, row
        # On a desktop every key stays on one line.
        assert [r["key"] for r in wide if r["key_lines"] != 1] == []
        # An integer is shown whole: the seed, not 2.02406e+07.
        assert keys["tolerances.seed"]["value"] == "20240611"
        inputs = phone.locator("#inputs")
        inputs.scroll_into_view_if_needed()
        phone.screenshot(path=str(SHOTS / "report-390-inputs.png"))
    finally:
        phone.context.close()
        desk.context.close()


def test_print_shows_every_column(browser: Any, report: Path) -> None:
    """The boxes scroll on a screen only: printed (``ecdsim report --pdf``) a wide table is
    laid out as before, not cut at the box's edge."""
    page = _open(browser, report, 1280)
    try:
        page.emulate_media(media="print")
        overflow = page.evaluate(
            "[...document.querySelectorAll('.scroll')].map(b => getComputedStyle(b).overflowX)"
        )
        assert overflow
        assert set(overflow) == {"visible"}
    finally:
        page.context.close()


@pytest.fixture(scope="module")
def wing_report(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """A wing file's report (docs/wing.md, the report): the three-panel stick-slip ground
    test, a hinge stuck (a warning), every table of the wing section."""
    out = tmp_path_factory.mktemp("wing") / "wing.html"
    config = ROOT / "validation" / "configs" / "wing_three_panel_stick_slip_ground_test.toml"
    result = CliRunner().invoke(app, ["report", str(config), "-o", str(out)])
    assert result.exit_code == 0, result.output
    return out


@pytest.mark.parametrize("width", [390, 1280])
def test_wing_report_fits_the_screen(browser: Any, wing_report: Path, width: int) -> None:
    page = _open(browser, wing_report, width)
    try:
        page.screenshot(path=str(SHOTS / f"wing-report-{width}.png"), full_page=True)
        assert page.evaluate("document.documentElement.scrollWidth") == width
        tables = page.evaluate(TABLE_LAYOUT)
        names = [t["name"] for t in tables]
        assert names == ["provenance", "wing-deployment", "wing-latches", "wing-energy"]
        for table in tables[1:]:
            box = table["box"]
            assert box is not None, table
            assert box["right"] <= width, table
            assert box["tabindex"] == "0", table
            assert box["role"] == "region", table
        scrolling = {t["name"] for t in tables if t["box"] and t["box"]["scrolls"]}
        # The latch table is wider than a phone: it scrolls in its box; on a desktop none.
        assert ("wing-latches" in scrolling) == (width == 390)
        _axe(page)
    finally:
        page.context.close()
