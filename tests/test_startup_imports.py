"""Each command imports only what it uses (issue 13, item 4).

Every case runs one command in a fresh interpreter, in process through the typer app
(``ecdsim.cli.app.main`` with its output captured), then lists the top-level packages
loaded. Heavy packages the command does not use must be absent: jinja2 (the HTML
report), matplotlib (plots), pandas (Monte Carlo tables), scipy where no integration
runs (the drop-test fit's least squares and distributions are ecdsim's own,
characterize/leastsq.py and distributions.py), pint where every unit is in the lean
table, dask (pint imports it).
No wall-clock assertion: timings are benchmarks (benchmarks/bench_startup.py).
"""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]

SCRIPT = """
import contextlib, io, json, sys
from ecdsim.cli.app import main
sys.argv = ["ecdsim", *sys.argv[1:]]
code = 0
with contextlib.redirect_stdout(io.StringIO()), contextlib.redirect_stderr(io.StringIO()):
    try:
        main()
    except SystemExit as exit:
        code = exit.code or 0
own = sorted(m for m in sys.modules if m.startswith("ecdsim."))
top = sorted({m.split(".")[0] for m in sys.modules})
print(json.dumps({"code": code, "modules": top, "ecdsim": own}))
"""

NEVER_FOR_THESE = ("jinja2", "matplotlib", "pandas", "dask", "pint")
# markdown_it: rich.markdown, which typer's help renderer (typer.rich_utils) imports, about
# 40 ms; a command that prints no help has no use for it.
NOT_FOR_A_RUN = (*NEVER_FOR_THESE, "scipy", "markdown_it")
CASES = [
    (["--help"], (*NEVER_FOR_THESE, "scipy", "numpy", "pydantic")),
    (["deploy", "examples/paper_cc16.toml"], NOT_FOR_A_RUN),
    (["deploy", "examples/paper_cc16.toml", "--json"], NOT_FOR_A_RUN),
    (["fit", "drop-test", "examples/drop_test.csv"], NOT_FOR_A_RUN),
    (["fit", "drop-test", "examples/drop_test.csv", "--json"], NOT_FOR_A_RUN),
]


def loaded(arguments: list[str], own: bool = False) -> tuple[int, list[str]]:
    """Exit code and top-level modules loaded by ``ecdsim *arguments`` run in process
    (with ``own``: ecdsim's own modules instead)."""
    done = subprocess.run(
        [sys.executable, "-c", SCRIPT, *arguments],
        cwd=ROOT,
        capture_output=True,
        text=True,
        check=True,
    )
    result = json.loads(done.stdout.strip().splitlines()[-1])
    return int(result["code"]), list(result["ecdsim" if own else "modules"])


@pytest.mark.parametrize(("arguments", "absent"), CASES, ids=[" ".join(c[0]) for c in CASES])
def test_command_imports_only_what_it_uses(arguments: list[str], absent: tuple[str, ...]) -> None:
    code, modules = loaded(arguments)
    assert code == 0
    assert [m for m in absent if m in modules] == []


def test_the_check_sees_what_a_command_uses() -> None:
    # The fit uses numpy, and deploy numpy and pydantic: were the listing broken, the
    # absence checks above would pass vacuously (and --help, which renders with
    # typer.rich_utils, loads markdown_it).
    _, fit_modules = loaded(["fit", "drop-test", "examples/drop_test.csv"])
    _, deploy_modules = loaded(["deploy", "examples/paper_cc16.toml"])
    _, help_modules = loaded(["--help"])
    assert "numpy" in fit_modules
    assert {"numpy", "pydantic", "ecdsim"} <= set(deploy_modules)
    assert "markdown_it" in help_modules


def test_quasi_static_deploy_and_a_printed_fit_skip_what_they_do_not_run() -> None:
    # The dynamic solver (lazy in ecdsim.methods) and the config schema (built by a fit
    # only when it writes a parameter file) are ecdsim's own heaviest imports.
    _, deploy_own = loaded(["deploy", "examples/paper_cc16.toml"], own=True)
    _, fit_own = loaded(["fit", "drop-test", "examples/drop_test.csv"], own=True)
    assert "ecdsim.dynamics.solver" not in deploy_own
    assert "ecdsim.config.schema" not in fit_own
    assert "ecdsim.characterize.droptest" in fit_own


def test_a_config_without_study_sections_skips_their_schemas() -> None:
    # [requirements], [fluid_damper] and [tolerances] have schemas of their own (~15 ms
    # to import); a file without them is validated without them, one with them by the
    # whole schema (so that the check is not vacuous: sizing.toml has [requirements]).
    study = {
        "ecdsim.config.full_schema",
        "ecdsim.config.sizing_schema",
        "ecdsim.config.tolerance_schema",
    }
    _, paper = loaded(["deploy", "examples/paper_cc16.toml"], own=True)
    _, sizing = loaded(["deploy", "examples/sizing.toml"], own=True)
    assert study.isdisjoint(paper)
    assert study <= set(sizing)


def test_reading_a_config_does_not_scan_for_pydantic_plugins() -> None:
    # pydantic's first validator build reads every installed distribution's entry points
    # looking for plugins (~10 ms); the config schema is built with plugins off, and
    # typer builds its option adapters so. Record any such scan during a deploy.
    script = """
import contextlib, importlib.metadata, io, sys
scans = []
real = importlib.metadata.entry_points
def recording(**kwargs):
    scans.append(kwargs)
    return real(**kwargs)
importlib.metadata.entry_points = recording
from ecdsim.cli.app import main
sys.argv = ["ecdsim", "deploy", "examples/paper_cc16.toml"]
with contextlib.redirect_stdout(io.StringIO()):
    try:
        main()
    except SystemExit:
        pass
print(len(scans), "PYDANTIC_DISABLE_PLUGINS" in __import__("os").environ)
"""
    done = subprocess.run(
        [sys.executable, "-c", script], cwd=ROOT, capture_output=True, text=True, check=True
    )
    # No scan, and the variable is not left set for the user's own models.
    assert done.stdout.split() == ["0", "False"]


def test_start_up_loads_the_modules_docs_architecture_names() -> None:
    # docs/architecture.md, "Start-up": importing the command line loads typer, the
    # version, the two formatting modules and the CLI's own modules, and nothing else of
    # ecdsim (each command imports the library inside its function).
    script = (
        "import sys, json; import ecdsim.cli.app; "
        "print(json.dumps(sorted(m for m in sys.modules if m.startswith('ecdsim'))))"
    )
    done = subprocess.run(
        [sys.executable, "-c", script], cwd=ROOT, capture_output=True, text=True, check=True
    )
    modules = json.loads(done.stdout)
    documented = {"ecdsim", "ecdsim._version", "ecdsim.formatting", "ecdsim.units_display"}
    assert [m for m in modules if m not in documented and not m.startswith("ecdsim.cli")] == []
    assert "ecdsim.cli.render" not in modules  # rich: imported by the tables, when printed
    text = (ROOT / "docs" / "architecture.md").read_text(encoding="utf-8")
    assert all(f"`{m}`" in text for m in sorted(documented - {"ecdsim"}))
