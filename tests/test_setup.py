"""The README's set-up: make test installs chromium itself or stops with one line.

Issue 11, item 1: the browser tests are never skipped; where chromium cannot be
installed, ``make test`` stops at once naming the package.
"""

from __future__ import annotations

import os
import shutil
import subprocess
from pathlib import Path

import pytest

from tests.conftest import ROOT

SCRIPT = ROOT / "scripts" / "ensure-chromium.sh"


def _run_script(
    tmp_path: Path, script: Path, env: dict[str, str], fakes: dict[str, str] | None = None
) -> subprocess.CompletedProcess[str]:
    """Run ``script`` with ``env`` added and a PATH that holds only bash and ``fakes``
    (name -> shell script body)."""
    bin_dir = tmp_path / "bin"
    bin_dir.mkdir()
    bash = shutil.which("bash")
    assert bash is not None
    (bin_dir / "bash").symlink_to(bash)
    for name, body in (fakes or {}).items():
        (bin_dir / name).write_text(f"#!{bash}\n{body}")
        (bin_dir / name).chmod(0o755)
    return subprocess.run(
        [bash, str(script)],
        env={**os.environ, "PATH": str(bin_dir), **env},
        capture_output=True,
        text=True,
        check=False,
    )


def _run_ensure_chromium(
    tmp_path: Path, fakes: dict[str, str] | None = None
) -> subprocess.CompletedProcess[str]:
    """ensure-chromium.sh for a chromium that is not there (:func:`_run_script`)."""
    return _run_script(tmp_path, SCRIPT, {"ECDSIM_CHROMIUM": str(tmp_path / "chromium")}, fakes)


def test_missing_chromium_without_apt_stops_with_one_line(tmp_path: Path) -> None:
    # A PATH that has bash but no apt-get, and a chromium that is not there.
    result = _run_ensure_chromium(tmp_path)
    assert result.returncode == 2
    lines = result.stderr.strip().splitlines()
    assert len(lines) == 1, result.stderr
    assert "'chromium'" in lines[0]
    assert "apt-get is not available" in lines[0]


def test_missing_chromium_without_root_stops_with_one_line(tmp_path: Path) -> None:
    # apt-get is there but the user is not root and has no password-less sudo: one line
    # with the command to run, exit 2, and apt-get never called. Fakes on the PATH: an
    # apt-get that records a call, an id that answers uid 1000, no sudo.
    called = tmp_path / "apt-get-called"
    result = _run_ensure_chromium(tmp_path, {"apt-get": f"touch {called}\n", "id": "echo 1000\n"})
    assert result.returncode == 2
    assert result.stderr.strip().splitlines() == [
        "error: "
        + str(tmp_path / "chromium")
        + " is missing and installing it needs root: run 'sudo apt-get install -y chromium', "
        "then rerun make test"
    ]
    assert not called.exists()


def test_present_chromium_is_left_alone(tmp_path: Path) -> None:
    fake = tmp_path / "chromium"
    fake.write_text("#!/bin/sh\n")
    fake.chmod(0o755)
    env = {**os.environ, "ECDSIM_CHROMIUM": str(fake)}
    result = subprocess.run(
        ["bash", str(SCRIPT)], env=env, capture_output=True, text=True, check=False
    )
    assert (result.returncode, result.stdout, result.stderr) == (0, "", "")


def test_make_test_installs_the_browser_and_ci_only_calls_make_test() -> None:
    makefile = (ROOT / "Makefile").read_text()
    assert "\ntest: browser " in makefile  # the browser first: stop before a long run
    ci = [
        line
        for line in (ROOT / ".ci" / "run").read_text().splitlines()
        if line.strip() and not line.startswith("#")
    ]
    assert ci[-1] == "make test"
    assert not any("apt-get" in line or "pip install" in line for line in ci)


AXE_SCRIPT = ROOT / "scripts" / "ensure-axe.sh"


def test_missing_npm_without_apt_stops_with_one_line(tmp_path: Path) -> None:
    # axe-core absent (an empty prefix), no npm and no apt-get on the PATH: one line
    # naming Debian's npm package, exit 2, before anything is installed.
    env = {"ECDSIM_AXE_PREFIX": str(tmp_path / "axe"), "ECDSIM_NPM": "npm-that-is-not-there"}
    result = _run_script(tmp_path, AXE_SCRIPT, env)
    assert result.returncode == 2
    lines = result.stderr.strip().splitlines()
    assert len(lines) == 1, result.stderr
    assert "'npm'" in lines[0]
    assert not (tmp_path / "axe").exists()


def test_a_missing_test_dependency_fails_with_the_install_command() -> None:
    # conftest.require is how a test imports an optional package: a failure naming the
    # package and the install command, never a skip (issue 11, item 9).
    from tests.conftest import INSTALL_TEST_EXTRA, require

    with pytest.raises(pytest.fail.Exception) as info:
        require("ecdsim_no_such_package")
    assert str(info.value) == f"ecdsim_no_such_package is missing: {INSTALL_TEST_EXTRA}"
    assert require("numpy").__name__ == "numpy"


def test_no_test_skips() -> None:
    # A skip turns a missing package or browser into a green run: none anywhere.
    needles = ("importorskip", "pytest.skip", "mark.skip", "skipif", "mark.xfail")
    this = Path(__file__).resolve()
    found = [
        f"{path.relative_to(ROOT)}:{number}: {line.strip()}"
        for folder in ("tests", "validation", "benchmarks")
        for path in sorted((ROOT / folder).rglob("*.py"))
        if path.resolve() != this
        for number, line in enumerate(path.read_text().splitlines(), 1)
        if any(needle in line for needle in needles) and not line.lstrip().startswith(("#", "``"))
    ]
    assert found == []
