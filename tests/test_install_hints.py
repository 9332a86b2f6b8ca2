"""Every message about a missing optional package names this installation's install command.

From a checkout (the tests run from its editable install) that is the checkout's
``python -m pip install -e '.[extra]'``; from an installed wheel, the package index's
``pip install 'ecdsim[extra]'`` (``ecdsim.invocation``, a foundation module that every
layer reporting a missing extra uses). Each message is produced here with the optional
package hidden (``sys.modules[name] = None`` makes its import fail) and read whole.
"""

from __future__ import annotations

import sys
from pathlib import Path

import pytest
from typer.testing import CliRunner

import ecdsim
from ecdsim import invocation
from ecdsim.cli.app import app
from tests.conftest import ROOT, messages

PAPER = ROOT / "examples" / "paper_cc16.toml"
DYNAMIC = ROOT / "examples" / "paper_cc16_dynamic.toml"


@pytest.fixture(autouse=True)
def _in_the_checkout(monkeypatch: pytest.MonkeyPatch) -> None:
    """Run from the checkout's root, where its install command is ``-e '.[extra]'``."""
    monkeypatch.chdir(ROOT)


def _hide(monkeypatch: pytest.MonkeyPatch, *names: str) -> None:
    for name in names:
        monkeypatch.setitem(sys.modules, name, None)


def _ends_with_this_install(message: str, extra: str) -> None:
    assert "\n" not in message
    assert message.endswith(f"install it with: {invocation.pip_install(extra)}"), message
    # this checkout's own command, not the package index's
    assert message.endswith(f" -m pip install -e '.[{extra}]'"), message
    assert "'ecdsim[" not in message


def test_the_hint_names_the_index_outside_a_checkout(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setattr(invocation, "checkout", lambda: None)
    assert invocation.install_hint("app").endswith(" -m pip install 'ecdsim[app]'")


def test_notebook_to_dataframe_without_pandas(monkeypatch: pytest.MonkeyPatch) -> None:
    result = ecdsim.deploy(PAPER, 25, "exact")
    _hide(monkeypatch, "pandas")
    with pytest.raises(ecdsim.api.MissingDependencyError) as caught:
        result.to_dataframe()
    assert str(caught.value).startswith("to_dataframe() needs pandas, which is not installed")
    _ends_with_this_install(str(caught.value), "montecarlo")


def test_montecarlo_without_pyarrow(monkeypatch: pytest.MonkeyPatch, tmp_path: Path) -> None:
    from ecdsim.montecarlo import MissingDependency
    from ecdsim.montecarlo.store import require

    _hide(monkeypatch, "pyarrow", "pyarrow.parquet")
    with pytest.raises(MissingDependency) as caught:
        require("pyarrow.parquet")
    assert str(caught.value).startswith("the Monte Carlo needs pyarrow, which is not installed")
    _ends_with_this_install(str(caught.value), "montecarlo")
    # and the command line prints that line as its error, exit 2
    tolerances = ROOT / "examples" / "paper_cc16_tolerances.toml"
    out = tmp_path / "study"
    result = CliRunner().invoke(app, ["montecarlo", str(tolerances), "-n", "8", "--out", str(out)])
    assert result.exit_code == 2, result.output
    (line,) = [m for m in messages(result.stderr) if m.startswith("error:")]
    _ends_with_this_install(line, "montecarlo")
    assert not list(out.glob("chunks/*.parquet"))


def test_sweep_parquet_without_pyarrow(monkeypatch: pytest.MonkeyPatch, tmp_path: Path) -> None:
    swept = ecdsim.sweep(PAPER, {"gearbox.ratio": [300, 400]}, temperatures=25, methods="exact")
    _hide(monkeypatch, "pyarrow", "pyarrow.parquet")
    with pytest.raises(ModuleNotFoundError) as caught:
        swept.write(tmp_path / "s.parquet")
    assert str(caught.value).startswith("Parquet output needs pyarrow")
    _ends_with_this_install(str(caught.value), "montecarlo")
    assert not (tmp_path / "s.parquet").exists()


def test_app_without_its_extra(monkeypatch: pytest.MonkeyPatch) -> None:
    _hide(monkeypatch, "uvicorn")
    result = CliRunner().invoke(app, ["app", str(PAPER)])
    assert result.exit_code == 2, result.output
    (line,) = messages(result.stderr)
    assert "ecdsim app needs the optional 'app' extra (missing module 'uvicorn')" in line
    _ends_with_this_install(line, "app")


def test_deployment_fmu_without_pythonfmu(monkeypatch: pytest.MonkeyPatch, tmp_path: Path) -> None:
    from ecdsim.fmu import FmuDependencyError, build_fmu

    _hide(monkeypatch, "pythonfmu", "pythonfmu.builder")
    with pytest.raises(FmuDependencyError) as caught:
        build_fmu(DYNAMIC, tmp_path / "deployment.fmu", deployment=True)
    assert str(caught.value).startswith("the deployment FMU is built with pythonfmu")
    _ends_with_this_install(str(caught.value), "fmu")
    assert not (tmp_path / "deployment.fmu").exists()
