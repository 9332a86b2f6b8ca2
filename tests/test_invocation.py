"""The commands ecdsim tells a user to type work where they are typed (issue 23 item 3).

After `make demo` ecdsim is `.venv/bin/ecdsim`, not on the PATH, and the checkout is
installed in development mode: the demo's "then:" line and the FMU export's install hint
name the commands of this installation (ecdsim.invocation), not `ecdsim` and an
install from the package index.
"""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import pytest

from ecdsim import invocation
from tests.conftest import ROOT

SCRIPT = Path(sys.executable).parent / "ecdsim"  # the console script beside this Python


def _path_without(folder: Path) -> str:
    """PATH without ``folder`` (as in a shell where the venv is not activated)."""
    kept = [p for p in os.environ.get("PATH", "").split(os.pathsep) if Path(p) != folder]
    return os.pathsep.join(kept)


def test_the_command_is_the_path_it_was_started_by_when_not_on_the_path(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    monkeypatch.chdir(ROOT)
    monkeypatch.setenv("PATH", _path_without(SCRIPT.parent))
    shown = invocation.ecdsim_command(str(SCRIPT))
    expected = SCRIPT.relative_to(ROOT) if SCRIPT.is_relative_to(ROOT) else SCRIPT
    assert Path(shown) == expected  # .venv/bin/ecdsim from the checkout
    monkeypatch.setenv("PATH", f"{SCRIPT.parent}{os.pathsep}{os.environ['PATH']}")
    assert invocation.ecdsim_command(str(SCRIPT)) == "ecdsim"  # the venv activated
    # python -m ecdsim (argv[0] is the package's __main__.py), a notebook: the plain name
    assert invocation.ecdsim_command("/somewhere/ecdsim/__main__.py") == "ecdsim"


def test_demo_prints_the_command_that_runs_here(tmp_path: Path) -> None:
    assert SCRIPT.is_file(), f"ecdsim console script not installed next to {sys.executable}"
    env = {**os.environ, "PATH": _path_without(SCRIPT.parent), "COLUMNS": "80"}
    done = subprocess.run(
        [str(SCRIPT), "demo", "--out", "demo"],
        cwd=tmp_path,
        env=env,
        capture_output=True,
        text=True,
        check=False,
    )
    assert done.returncode == 0, done.stderr
    line = f"edit it, then: {SCRIPT} deploy {Path('demo') / 'paper_cc16.toml'}"
    assert line in done.stdout.splitlines()
    # and that command runs, as printed
    again = subprocess.run(
        [str(SCRIPT), "deploy", "demo/paper_cc16.toml"],
        cwd=tmp_path,
        env=env,
        capture_output=True,
        text=True,
        check=False,
    )
    assert again.returncode == 0, again.stderr


def test_the_install_hint_of_a_checkout_installs_the_checkout(
    monkeypatch: pytest.MonkeyPatch, tmp_path: Path
) -> None:
    assert invocation.checkout() == ROOT  # the tests run from an editable install
    monkeypatch.chdir(ROOT)
    assert invocation.pip_install("fmu").endswith(" -m pip install -e '.[fmu]'")
    monkeypatch.chdir(ROOT / "examples")
    assert invocation.pip_install("fmu").endswith(" -m pip install -e '..[fmu]'")
    # From an installed wheel (no checkout): the package index.
    monkeypatch.setattr(invocation, "checkout", lambda: None)
    assert invocation.pip_install("fmu").endswith(" -m pip install 'ecdsim[fmu]'")


def test_export_fmu_without_pythonfmu_names_this_checkouts_install(tmp_path: Path) -> None:
    # The deployment FMU is built with pythonfmu (the damper FMU with a C compiler).
    fake = tmp_path / "fake" / "pythonfmu"
    fake.mkdir(parents=True)
    (fake / "__init__.py").write_text('raise ImportError("not installed")\n', encoding="utf-8")
    (fake / "builder.py").write_text('raise ImportError("not installed")\n', encoding="utf-8")
    env = {**os.environ, "PYTHONPATH": os.pathsep.join([str(fake.parent), str(ROOT)])}
    out = tmp_path / "deployment.fmu"
    dynamic = ROOT / "examples" / "paper_cc16_dynamic.toml"
    done = subprocess.run(
        [
            sys.executable,
            "-m",
            "ecdsim",
            "export-fmu",
            str(dynamic),
            "--deployment",
            "-o",
            str(out),
        ],
        cwd=ROOT,
        env=env,
        capture_output=True,
        text=True,
        check=False,
    )
    assert done.returncode == 2, done.stdout + done.stderr
    (line,) = done.stderr.splitlines()
    assert line.startswith("error: "), line
    assert "pythonfmu, which is not installed" in line
    assert line.endswith(" -m pip install -e '.[fmu]'"), line
    assert not out.exists()


def test_export_fmus_help_names_the_same_install_as_its_error(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    from typer.testing import CliRunner

    from ecdsim.cli.app import app
    from ecdsim.cli.display import with_install_commands

    monkeypatch.chdir(ROOT)
    wide = {"COLUMNS": "250", "TERMINAL_WIDTH": "250"}  # the command on one line
    shown = CliRunner().invoke(app, ["export-fmu", "--help"], env=wide).output
    # The checkout's own command, as the error above says it; not the package index.
    assert f"pythonfmu to build ({invocation.pip_install('fmu')})" in shown
    assert invocation.pip_install("fmu").endswith(" -m pip install -e '.[fmu]'")
    assert "'ecdsim[fmu]'" not in shown
    # From an installed wheel: the package index, its brackets escaped for rich markup.
    monkeypatch.setattr(invocation, "checkout", lambda: None)
    filled = with_install_commands("build ({install:fmu})")
    assert filled.startswith("build (")
    assert filled.endswith(" -m pip install 'ecdsim\\[fmu]')")
