"""Shared fixtures: the paper's Cc-16 example built directly from the paper's constants."""

from __future__ import annotations

import importlib
import re
from collections.abc import Generator
from pathlib import Path
from types import ModuleType
from typing import TYPE_CHECKING, Any

import pytest

from ecdsim.model import (
    DeploymentSystem,
    Ecd,
    Gearbox,
    HighSpeedDamper,
    LinearSpring,
    LinearTemperatureLaw,
    Load,
)

if TYPE_CHECKING:
    from matplotlib.axes import Axes
    from matplotlib.figure import Figure

ROOT = Path(__file__).resolve().parent.parent
PAPER_CONFIG = ROOT / "examples" / "paper_cc16.toml"
# The test extra holds every package the tests import beyond the core dependencies; a
# missing one fails its tests with this command, never skips them.
INSTALL_TEST_EXTRA = (
    "install the test dependencies: .venv/bin/python -m pip install -e '.[test]' "
    "(make test does it)"
)


def _with_install_hint(report: pytest.CollectReport | pytest.TestReport) -> None:
    text = str(report.longrepr)
    missing = re.search(r"ModuleNotFoundError: No module named '([^']+)'", text)
    if report.failed and missing and INSTALL_TEST_EXTRA not in text:
        # First line: pytest's short summary shows it.
        report.longrepr = f"{missing.group(1)} is missing: {INSTALL_TEST_EXTRA}\n\n{text}"


def require(name: str) -> ModuleType:
    """Import an optional test dependency, or fail (never skip) with the install command.

    ``pytest.importorskip`` would report a missing package as a skip, which a green run
    hides (issue 11, item 9): every package the tests import is in the test extra.
    """
    try:
        return importlib.import_module(name)
    except ModuleNotFoundError as error:
        pytest.fail(f"{error.name} is missing: {INSTALL_TEST_EXTRA}", pytrace=False)


def pytest_collectreport(report: pytest.CollectReport) -> None:
    """A test module importing a missing package fails with the install command."""
    _with_install_hint(report)


@pytest.hookimpl(wrapper=True)
def pytest_runtest_makereport(
    item: pytest.Item, call: pytest.CallInfo[None]
) -> Generator[None, pytest.TestReport, pytest.TestReport]:
    """A test importing a missing package inside its body: the same install command."""
    report = yield
    _with_install_hint(report)
    return report


def messages(stderr: str) -> list[str]:
    """The ``warning:``/``note:`` messages of a command's stderr, each on one line again:
    the CLI wraps them to the terminal's width, continuation lines indented."""
    found: list[str] = []
    for line in stderr.splitlines():
        if line.startswith("  ") and found:
            found[-1] += " " + line.strip()
        else:
            found.append(line)
    return found


def paper_system(**load_overrides: float) -> DeploymentSystem:
    """The paper's section 6 example, every constant as printed in the paper."""
    damper = HighSpeedDamper(
        damping_rate=1.3e-4,
        coulomb_friction=7.9e-4,
        lubrication_friction=LinearTemperatureLaw(slope=-2.12e-6, at_0c=2.2e-4),
    )
    gearbox = Gearbox(ratio=380.0, coulomb_friction=4.5e-4, damping_fraction=0.26)
    start = load_overrides.get("start_torque", 3.73)
    end = load_overrides.get("end_torque", 1.58)
    travel = load_overrides.get("travel", 1.57)
    load = Load(
        spring=LinearSpring(start, end),
        travel=travel,
        system_friction=LinearTemperatureLaw(slope=-0.0044, at_0c=0.58),
    )
    return DeploymentSystem(Ecd(damper, gearbox), load, name="paper Cc-16")


@pytest.fixture
def paper() -> DeploymentSystem:
    """The paper's example system."""
    return paper_system()


class SavedFigures:
    """The matplotlib figures a command saved, by file name, as they were drawn.

    Plot tests assert what a reader sees (titles, axis labels with units, legend
    entries, the plotted numbers), which a PNG's bytes do not show.
    """

    def __init__(self) -> None:
        self.figures: dict[str, Figure] = {}

    def record(self, target: object, figure: Figure) -> None:
        # ecdsim.atomic writes to ".<name>.<random>.tmp" beside the target, then renames;
        # an in-memory buffer (an inline report figure) is named by its order.
        if isinstance(target, str | Path) or hasattr(target, "name"):
            name = Path(str(getattr(target, "name", target))).name
        else:
            name = f"buffer {len(self.figures) + 1}"
        if name.startswith(".") and name.endswith(".tmp"):
            name = name[1:].rsplit(".", 2)[0]
        self.figures[name] = figure

    def axes(self, name: str) -> list[Axes]:
        """The axes of the figure saved as ``name`` (fails if none was)."""
        assert name in self.figures, f"no figure saved as {name}: {sorted(self.figures)}"
        return list(self.figures[name].axes)

    def legend(self, axes: Axes) -> list[str]:
        """The legend entries of one axes."""
        legend = axes.get_legend()
        assert legend is not None, f"no legend on {axes.get_title()!r}"
        return [text.get_text() for text in legend.get_texts()]


@pytest.fixture
def saved_figures(monkeypatch: pytest.MonkeyPatch) -> SavedFigures:
    """Record every figure saved during the test (Figure.savefig still writes the file)."""
    from matplotlib.figure import Figure

    captured = SavedFigures()
    original = Figure.savefig

    def savefig(self: Figure, fname: Any, *args: Any, **kwargs: Any) -> None:
        captured.record(fname, self)
        original(self, fname, *args, **kwargs)

    monkeypatch.setattr(Figure, "savefig", savefig)
    return captured
