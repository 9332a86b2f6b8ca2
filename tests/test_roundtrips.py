"""Round trips a user makes (issue 14, item 10): make demo's config path, report -o folders,
and the test extra's dependencies."""

from __future__ import annotations

import tomllib
from pathlib import Path

import pytest
from typer.testing import CliRunner

from ecdsim.cli.app import app
from ecdsim.invocation import ecdsim_command
from tests.conftest import PAPER_CONFIG, ROOT

runner = CliRunner()


def test_demo_prints_a_config_path_that_exists(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    monkeypatch.chdir(tmp_path)  # anywhere, as after `pip install ecdsim`: no examples/ here
    result = runner.invoke(app, ["demo", "--out", "ecdsim-demo"])
    assert result.exit_code == 0, result.output
    lines = result.stdout.splitlines()
    (line,) = [line for line in lines if line.startswith("config: ")]
    path = Path(line.removeprefix("config: "))
    assert path == Path("ecdsim-demo") / "paper_cc16.toml"
    assert path.is_file()
    # It is the paper's example, and `ecdsim deploy` runs it as printed.
    assert tomllib.loads(path.read_text()) == tomllib.loads(PAPER_CONFIG.read_text())
    # The command as this process runs ecdsim (tests/test_invocation.py: .venv/bin/ecdsim
    # after make demo, where it is not on the PATH); each line fits 80 columns.
    assert f"edit it, then: {ecdsim_command()} deploy {path}" in lines
    assert runner.invoke(app, ["deploy", str(path)]).exit_code == 0


def test_report_says_when_it_creates_the_folder(tmp_path: Path) -> None:
    out = tmp_path / "new" / "deeper" / "report.html"
    result = runner.invoke(app, ["report", str(PAPER_CONFIG), "-o", str(out)])
    assert result.exit_code == 0, result.output
    assert out.is_file()
    notes = [line for line in result.stderr.splitlines() if line.startswith("note: created")]
    assert notes == [f"note: created the folder {out.parent} (it did not exist)"]
    again = runner.invoke(app, ["report", str(PAPER_CONFIG), "-o", str(out)])
    assert again.exit_code == 0, again.output
    assert "note: created" not in again.stderr  # it exists now: nothing to say


def test_the_test_extra_holds_what_the_tests_import_indirectly() -> None:
    extra = tomllib.loads((ROOT / "pyproject.toml").read_text())["project"]
    test_extra = extra["optional-dependencies"]["test"]
    # httpx2 is imported by no module of ours but by starlette's TestClient, which with
    # plain httpx only warns that it is deprecated: an error under the tests' warning
    # filters. Dropped once as "unused", it failed make test on a fresh clone.
    assert any(dep.startswith("httpx2") for dep in test_extra)
    import starlette.testclient

    # what the TestClient took: httpx2 when installed
    assert vars(starlette.testclient)["httpx"].__name__ == "httpx2"
    # tomlkit keeps the user's file in `fit -o`: a core dependency, importable.
    assert any(dep.startswith("tomlkit") for dep in extra["dependencies"])
