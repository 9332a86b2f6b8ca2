"""numba's set-up (ecdsim._numba, issue 23 items 2 and 8): the switch, the NumPy paths
where numba is missing, the compile notice, and the compiled cache of a read-only install.

The compiled kernels are checked against the NumPy paths number by number elsewhere
(tests/test_exact_kernel.py, tests/test_dynamics_kernel.py,
tests/test_montecarlo_streaming.py); here: that every entry point falls back where numba
cannot be imported (a platform without its wheels), that the dynamic kernel (compiled
from its own Python source by ecdsim.dynamics.kernel.build) obeys the same switch, that
a compile without a cache says so, that `ecdsim precompile` on a package folder
nobody can write leaves its kernels (the dynamic kernel's included) in the user's cache,
where the next process finds them, and that a process after precompile compiles none of
the kernels precompile reaches.
"""

from __future__ import annotations

import io
import json
import os
import re
import shlex
import shutil
import stat
import subprocess
import sys
import tempfile
from pathlib import Path

import pytest

from ecdsim import _numba
from tests.conftest import ROOT

# A numba that cannot be imported, as on a platform without its wheels: first on the
# path, it shadows the installed one.
FAKE_NUMBA = 'raise ImportError("no numba on this platform (a test stand-in)")\n'

# Every compiled entry point, asked what it runs where numba is missing, and each
# computation run by its NumPy path: the dynamic method (its kernel as plain Python: one
# case, a batch, a spring table), the exact kernel of a large batch and the Monte Carlo
# sums and brackets. Prints one JSON document.
WITHOUT_NUMBA = """
import json, sys
import numpy as np
from ecdsim import _numba
from ecdsim.cli import precompile
from ecdsim.deployment import predict
from ecdsim.api import load
from ecdsim.dynamics.kernel import build
from ecdsim.montecarlo import intervals, streaming
from ecdsim.solvers import exact_kernel

found = {
    "available": _numba.available(),
    "dynamic_kernel": build.backend().name,
    "exact_kernel": exact_kernel.choose(10**6),
    "compiled_sums": streaming.compiled_sums(10**6),
    "compiled_selection": intervals.compiled_selection(),
}
times = {}
for name, mapping, temps in [
    ("one case", precompile._heating_rolloff(), [25.0]),
    ("batch", precompile._heating_rolloff(), [-40.0, 25.0, 100.0]),
    ("table", precompile._spring_table(), [-40.0, 25.0]),
]:
    config = load(mapping)
    out = predict(config.system, temps, ["dynamic"], config.spec.dynamics())
    times[name] = np.ravel(out.solutions["dynamic"].deployment_time).tolist()
precompile._exact_batch()
found["times"] = times
found["numba_imported"] = sys.modules.get("numba") is not None
print(json.dumps(found))
"""


def _run(script: str, env: dict[str, str], cwd: Path = ROOT) -> subprocess.CompletedProcess[str]:
    return subprocess.run(
        [sys.executable, "-c", script],
        cwd=cwd,
        env=env,
        capture_output=True,
        text=True,
        check=False,
    )


def test_without_numba_every_entry_point_takes_the_numpy_path(tmp_path: Path) -> None:
    fake = tmp_path / "fake" / "numba"
    fake.mkdir(parents=True)
    (fake / "__init__.py").write_text(FAKE_NUMBA, encoding="utf-8")
    env = {**os.environ, "PYTHONPATH": os.pathsep.join([str(fake.parent), str(ROOT)])}
    env.pop("ECDSIM_NUMBA", None)
    done = _run(WITHOUT_NUMBA, env)
    assert done.returncode == 0, done.stderr
    found = json.loads(done.stdout)
    assert found["available"] is False
    assert found["dynamic_kernel"] == "python"
    assert found["exact_kernel"] == "numpy"
    assert found["compiled_sums"] is False
    assert found["compiled_selection"] is False
    assert found["numba_imported"] is False
    # The same deployments with the compiled kernel, in this process: the plain and the
    # compiled kernel are the same functions (ecdsim.dynamics.kernel.build), at the same
    # rtol (1e-8 per step); they differ only in rounding (fused or reordered operations),
    # and 1e-7 is docs/dynamics.md's stated accuracy of a time.
    import numpy as np

    from ecdsim.api import load
    from ecdsim.cli import precompile
    from ecdsim.deployment import predict

    cases = {
        "one case": (precompile._heating_rolloff(), [25.0]),
        "batch": (precompile._heating_rolloff(), [-40.0, 25.0, 100.0]),
        "table": (precompile._spring_table(), [-40.0, 25.0]),
    }
    for name, (mapping, temps) in cases.items():
        config = load(mapping)
        out = predict(config.system, temps, ["dynamic"], config.spec.dynamics())
        compiled = np.ravel(out.solutions["dynamic"].deployment_time)
        assert np.all(np.isfinite(compiled)), name
        np.testing.assert_allclose(found["times"][name], compiled, rtol=1e-7, err_msg=name)


def test_precompile_without_numba_names_the_install_command(tmp_path: Path) -> None:
    fake = tmp_path / "fake" / "numba"
    fake.mkdir(parents=True)
    (fake / "__init__.py").write_text(FAKE_NUMBA, encoding="utf-8")
    env = {**os.environ, "PYTHONPATH": os.pathsep.join([str(fake.parent), str(ROOT)])}
    env.pop("ECDSIM_NUMBA", None)
    done = subprocess.run(
        [sys.executable, "-m", "ecdsim", "precompile"],
        cwd=ROOT,
        env=env,
        capture_output=True,
        text=True,
        check=False,
    )
    assert done.returncode == 1
    (line,) = done.stderr.splitlines()
    assert line.startswith("numba is not installed: ecdsim runs its NumPy paths")
    assert line.endswith("-m pip install -e '.[numba]'"), line  # this checkout's own


def test_the_switch_turns_every_compiled_path_off(monkeypatch: pytest.MonkeyPatch) -> None:
    from ecdsim.dynamics.kernel import build
    from ecdsim.montecarlo import intervals, streaming
    from ecdsim.solvers import exact_kernel

    monkeypatch.setenv("ECDSIM_NUMBA", "0")
    monkeypatch.delenv("ECDSIM_EXACT_KERNEL", raising=False)
    assert _numba.switched_off()
    assert not _numba.enabled()
    assert build.backend().name == "python"  # the dynamic kernel's plain form
    assert exact_kernel.choose(10**6) == "numpy"
    assert not streaming.compiled_sums(10**6)
    assert not intervals.compiled_selection()
    monkeypatch.setenv("ECDSIM_NUMBA", "1")
    assert _numba.enabled()
    assert build.backend().name == "numba"
    assert exact_kernel.choose(10**6) == "numba"


class _Terminal(io.StringIO):
    def isatty(self) -> bool:
        return True


@pytest.fixture
def fresh_notice(monkeypatch: pytest.MonkeyPatch) -> None:
    """The notice not yet printed in this process, the environment's choice unset."""
    monkeypatch.setitem(_numba._state, "noticed", False)
    monkeypatch.delenv(_numba.NOTICE, raising=False)


@pytest.mark.usefixtures("fresh_notice")
def test_the_notice_goes_to_a_terminal_once() -> None:
    terminal = _Terminal()
    _numba.notice(terminal)
    _numba.notice(terminal)
    assert terminal.getvalue() == _numba.NOTICE_TEXT + "\n"  # once per process


@pytest.mark.usefixtures("fresh_notice")
def test_the_notice_stays_out_of_pipes_unless_asked(monkeypatch: pytest.MonkeyPatch) -> None:
    pipe = io.StringIO()
    _numba.notice(pipe)
    assert pipe.getvalue() == ""  # the output of a command never depends on a cache
    monkeypatch.setenv(_numba.NOTICE, "1")
    _numba.notice(pipe)
    assert pipe.getvalue() == _numba.NOTICE_TEXT + "\n"
    monkeypatch.setitem(_numba._state, "noticed", False)
    monkeypatch.setenv(_numba.NOTICE, "0")
    terminal = _Terminal()
    _numba.notice(terminal)
    assert terminal.getvalue() == ""


@pytest.mark.usefixtures("fresh_notice")
def test_a_compile_without_a_cache_is_counted_and_announced(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    # A function numba has never seen (no disk cache: cache=False) compiles at its first
    # call: the listener counts it and prints the notice on a terminal stderr.
    _numba.load()
    import numba

    terminal = _Terminal()
    monkeypatch.setattr(sys, "stderr", terminal)
    before = _numba.compilations()

    @numba.njit(cache=False)
    def twice(x: float) -> float:
        return 2.0 * x

    assert twice(1.5) == 3.0
    assert _numba.compilations() > before
    assert terminal.getvalue() == _numba.NOTICE_TEXT + "\n"
    again = _numba.compilations()
    assert twice(2.5) == 5.0  # compiled already: no compile, no second notice
    assert _numba.compilations() == again
    assert terminal.getvalue() == _numba.NOTICE_TEXT + "\n"


def _read_only(folder: Path) -> None:
    """Take every write permission off ``folder``'s tree."""
    for path in [folder, *folder.rglob("*")]:
        mode = path.stat().st_mode
        path.chmod(mode & ~(stat.S_IWUSR | stat.S_IWGRP | stat.S_IWOTH))


def _can_mount_read_only() -> bool:
    """True if this root process can bind-mount a folder read-only in a mount namespace."""
    if shutil.which("unshare") is None:
        return False
    with tempfile.TemporaryDirectory() as folder:
        probe = f"mount --bind -o ro {folder} {folder} && ! touch {folder}/x 2>/dev/null"
        done = subprocess.run(
            ["unshare", "--mount", "sh", "-c", probe], capture_output=True, check=False
        )
        return done.returncode == 0


# ``ecdsim precompile`` (its command, its count and its report of the cache folder) with
# two small workloads, one for each kind of numba cache ecdsim compiles into: a module
# kernel with numba's own cache (the exact solution of a large batch), and the dynamic
# kernel's digest-keyed cache (ecdsim.dynamics.kernel.build), reached by its smallest
# entry point, the sampling of a trajectory (the deployment itself solved by the plain
# kernel, so that only the sampling compiles). Where a cache goes (beside the package, or
# the user's folder) is decided per cache class by numba's locators, the same for every
# kernel of a class: all of precompile's workloads compiled cold here took about 270 s
# of CPU (320 compilations), these two about 25 s. That every kernel precompile reaches
# is loaded by a later process is checked on the test install, whose cache the rest of
# the suite warms anyway (test_a_process_after_precompile_compiles_nothing).
SMALL_PRECOMPILE = """
import sys
from ecdsim.cli import precompile
from ecdsim.cli.precompile import Workload


def sample_a_trajectory():
    from ecdsim import _numba
    from ecdsim.api import load
    from ecdsim.deployment import predict

    config = load(precompile._dynamic_mapping())
    with _numba.plain():
        out = predict(config.system, [25.0], ["dynamic"], config.spec.dynamics())
    out.solutions["dynamic"].trajectory([0.0, 1.0, 2.0])


precompile.workloads = lambda: [
    Workload("exact: a batch", precompile._exact_batch),
    Workload("dynamic: a trajectory sampled", sample_a_trajectory),
]
from ecdsim.cli.app import main

sys.argv = ["ecdsim", "precompile"]
main()
"""


def _precompile_command(site: Path) -> list[str]:
    """``ecdsim precompile`` (:data:`SMALL_PRECOMPILE`) from the copy in ``site``, which no
    one can write.

    As a user, the permissions do it. As root (CI), whom permissions do not stop, the
    folder is bind-mounted read-only over itself in a mount namespace, as a system
    package on a read-only file system; where that is not allowed, a file named
    ``__pycache__`` in each package folder stops numba from making its cache folder there,
    which is what numba checks (it then uses the user's cache folder).
    """
    command = [sys.executable, "-c", SMALL_PRECOMPILE]
    if os.geteuid() != 0:
        return command
    if _can_mount_read_only():
        script = f"mount --bind -o ro {site} {site} && exec " + shlex.join(command)
        return ["unshare", "--mount", "sh", "-c", script]
    for folder in [p for p in site.rglob("*") if p.is_dir()]:
        if (folder / "__init__.py").exists():
            (folder / "__pycache__").write_text("not a folder", encoding="utf-8")
    return command


def _compilations(output: str) -> int:
    """The number precompile's last line gives: "done in ..., N compilations in this process"."""
    found = re.search(r"\b(\d+) compilations? in this process", output)
    assert found is not None, output
    return int(found.group(1))


@pytest.mark.slow
def test_a_read_only_install_compiles_once_into_the_user_cache(tmp_path: Path) -> None:
    # A system-wide install: the package in a folder nobody can write. The first
    # precompile (SMALL_PRECOMPILE's two workloads) compiles into the user's cache folder
    # (XDG_CACHE_HOME/numba), nothing beside the package; the second, a new process,
    # loads every kernel from there.
    site = tmp_path / "site"
    shutil.copytree(
        ROOT / "src" / "ecdsim", site / "ecdsim", ignore=shutil.ignore_patterns("__pycache__")
    )
    before = sorted(str(p.relative_to(site)) for p in site.rglob("*"))
    command = _precompile_command(site)
    _read_only(site)
    cache = tmp_path / "user-cache"
    env = {**os.environ, "PYTHONPATH": str(site), "XDG_CACHE_HOME": str(cache)}
    env["PYTHONDONTWRITEBYTECODE"] = "1"
    for key in ("NUMBA_CACHE_DIR", "ECDSIM_NUMBA", "NUMBA_DISABLE_JIT"):
        env.pop(key, None)
    runs = []
    for _ in range(2):
        done = subprocess.run(
            command, cwd=tmp_path, env=env, capture_output=True, text=True, check=False
        )
        assert done.returncode == 0, done.stdout + done.stderr
        runs.append(done.stdout)
    first, second = runs
    assert f"cached in\n{cache / 'numba'}" in first, first  # numba's user-wide folder
    # The count as a whole number: "320 compilations" also contains "0 compilations".
    assert _compilations(first) > 0, first
    assert _compilations(second) == 0, second
    assert "compilation" not in second.replace("0 compilations in this process", "")
    assert list((cache / "numba").rglob("*.nbi")), "no index in the user cache"
    assert list((cache / "numba").rglob("*.nbc")), "no machine code in the user cache"
    # Both kinds of cache went there: the dynamic kernel's entry point, the exact kernel.
    assert list((cache / "numba").rglob("sample.sample_cases-*.nbc")), "no dynamic kernel"
    assert list((cache / "numba").rglob("_exact_numba.ordinary-*.nbc")), "no exact kernel"
    after = sorted(str(p.relative_to(site)) for p in site.rglob("*") if p.name != "__pycache__")
    assert after == [b for b in before if not b.endswith("__pycache__")]
    for path in site.rglob("*"):
        path.chmod(path.stat().st_mode | stat.S_IWUSR)  # let tmp_path be removed


@pytest.mark.slow
def test_a_process_after_precompile_compiles_nothing(tmp_path: Path) -> None:
    # Every kernel that `ecdsim precompile`'s workloads reach (all of them, the Monte Carlo
    # study's in its own process) is cached and loaded by the next process, none compiled
    # again: in this install's cache, which the first run completes (the suite's other
    # tests have compiled most of it already).
    env = {k: v for k, v in os.environ.items() if k not in ("ECDSIM_NUMBA", "NUMBA_DISABLE_JIT")}
    runs = []
    for _ in range(2):
        done = subprocess.run(
            [sys.executable, "-m", "ecdsim", "precompile"],
            cwd=tmp_path,
            env=env,
            capture_output=True,
            text=True,
            check=False,
        )
        assert done.returncode == 0, done.stdout + done.stderr
        runs.append(done.stdout)
    second = runs[-1]
    assert "wing: two panels" in second, second  # every workload ran
    assert _compilations(second) == 0, second
    assert "compilation" not in second.replace("0 compilations in this process", "")


def test_plain_turns_every_compiled_path_off_for_a_block(monkeypatch: pytest.MonkeyPatch) -> None:
    # The deployment FMU's guard (ecdsim.fmu.slaves): inside plain() the dynamic kernel
    # runs its plain-Python form; after the block the switch is as the environment says.
    from ecdsim.dynamics.kernel import build

    monkeypatch.delenv(_numba.SWITCH, raising=False)
    with _numba.plain():
        assert _numba.switched_off()
        assert not _numba.enabled()
        assert build.backend().name == "python"
    assert not _numba.switched_off()
