"""``ecdsim precompile``: compile the numerical kernels ahead, so that no run waits for them.

The compiled kernels (numba, :mod:`ecdsim._numba`) are compiled on first use and cached
on disk for this CPU; the first dynamic run on a machine would otherwise spend a minute
or more compiling. This command runs a small representative set of computations instead of
naming kernels: whatever kernels those computations reach are compiled and cached, now
and after any rework of the solvers. ``make demo`` runs it; after ``pip install ecdsim``
a user runs it once (again after an upgrade). It prints each computation's time and
where the cache is; a second run loads everything from the cache in a few seconds.

Only typer is imported at start-up; the library inside the command.
"""

from __future__ import annotations

import os
import sys
import time
from collections.abc import Callable
from dataclasses import dataclass, replace
from pathlib import Path
from typing import Any

import typer

EPILOG = (
    "Example: [bold]ecdsim precompile[/bold]\n\n"
    "Compiles and caches the numba kernels for this CPU (once per installation; make demo "
    "runs it). The cache goes beside the package, or to ~/.cache/numba where the package "
    "folder is read-only, or to $NUMBA_CACHE_DIR (docs/reproducibility.md)."
)

# Cases of the large exact batch: above the exact solution's numba threshold
# (solvers.exact_kernel.NUMBA_MIN_CASES), checked when it runs.
EXACT_BATCH = 60_000
# Monte Carlo samples x 3 temperatures, above the same threshold (the compiled sums).
MONTECARLO_SAMPLES = 20_000


@dataclass(frozen=True)
class Workload:
    """One representative computation: its label and the function that runs it."""

    label: str
    run: Callable[[], None]
    # A note on the line (the Monte Carlo study compiles in its own process).
    note: str = ""


def _paper_mapping() -> dict[str, Any]:
    """The packaged paper example (section 6) as a TOML mapping."""
    import tomllib
    from importlib.resources import files

    text = (files("ecdsim") / "data" / "paper_cc16.toml").read_text(encoding="utf-8")
    return tomllib.loads(text)


def _with(mapping: dict[str, Any], **sections: dict[str, Any]) -> dict[str, Any]:
    """``mapping`` with keys added to (or set in) its sections."""
    out = {key: dict(value) if isinstance(value, dict) else value for key, value in mapping.items()}
    for name, keys in sections.items():
        section = dict(out.get(name, {}))
        section.update(keys)
        out[name] = section
    return out


# The dynamic example's additions to the paper's example (examples/paper_cc16_dynamic.toml).
_DYNAMIC_DAMPER = {"rotor_inertia": "2e-7 kg*m^2"}
_DYNAMIC_LOAD = {"inertia": "5 kg*m^2", "restitution": 0.0}
# Roll-off and self-heating, illustrative values of docs/dynamics.md's range.
_ROLLOFF = {"peak_speed": "2000 rad/s", "resistivity_coefficient": "0.0039 / K"}
_THERMAL = {"heat_capacity": "4 J/K", "thermal_resistance": "5 K/W"}


def _deploy(mapping: dict[str, Any], temperatures: list[float]) -> None:
    """``predict`` of the config ``mapping`` by every method it lists, as deploy runs it."""
    from ecdsim.api import load
    from ecdsim.deployment import predict

    config = load(mapping)
    methods = ["exact", "dynamic"]
    predict(config.system, temperatures, methods, config.spec.dynamics())


def _dynamic_mapping(**extra: dict[str, Any]) -> dict[str, Any]:
    base = _with(_paper_mapping(), damper=_DYNAMIC_DAMPER, load=_DYNAMIC_LOAD)
    return _with(base, **extra)


def _heating_rolloff() -> dict[str, Any]:
    mapping = _dynamic_mapping()
    mapping["damper"] = {**mapping["damper"], "rolloff": _ROLLOFF, "thermal": _THERMAL}
    return mapping


def _two_node() -> dict[str, Any]:
    mapping = _heating_rolloff()
    thermal = {**_THERMAL, "housing_heat_capacity": "90 J/K", "housing_thermal_resistance": "2 K/W"}
    mapping["damper"] = {**mapping["damper"], "thermal": thermal}
    return mapping


def _ground_test() -> dict[str, Any]:
    mapping = _dynamic_mapping(
        gearbox={"lost_motion": "0.25 deg"},
        damper={"stribeck_speed": "0.02 rad/s", "static_friction_factor": 1.3},
    )
    mapping["load"] = {
        **mapping["load"],
        "gravity": {"mass": "2.4 kg", "cg_radius": "0.35 m", "release_angle": "30 deg"},
        "resistive_table": [["0 deg", "0.2 N*m"], ["90 deg", "0.1 N*m"]],
    }
    return mapping


def _lossy_gear() -> dict[str, Any]:
    return _dynamic_mapping(
        gearbox={"efficiency": {"forward": 0.85, "backward": 0.8}, "coulomb_friction": "0 N*m"}
    )


def _compliant_mesh() -> dict[str, Any]:
    return _dynamic_mapping(
        gearbox={
            "lost_motion": "0.25 deg",
            "stiffness": "2000 N*m/rad",
            "mesh_damping": "5 N*m*s/rad",
        }
    )


def _spring_table() -> dict[str, Any]:
    mapping = _heating_rolloff()
    load = {k: v for k, v in mapping["load"].items() if k not in ("start_torque", "end_torque")}
    points = 40
    load["spring_table"] = [
        [f"{90.0 * i / (points - 1):.6g} deg", f"{3.73 - 2.15 * i / (points - 1):.6g} N*m"]
        for i in range(points)
    ]
    mapping["load"] = load
    return mapping


def _exact_batch() -> None:
    """The exact solution of a batch large enough for its compiled kernel."""
    import numpy as np

    from ecdsim.api import load
    from ecdsim.deployment import predict
    from ecdsim.solvers.exact_kernel import NUMBA_MIN_CASES

    assert EXACT_BATCH >= NUMBA_MIN_CASES
    config = load(_paper_mapping())
    ecd = config.system.ecd
    gearbox = replace(ecd.gearbox, ratio=np.linspace(300.0, 460.0, EXACT_BATCH))
    system = replace(config.system, ecd=replace(ecd, gearbox=gearbox))
    predict(system, np.array([[25.0]]), ["exact"])


def _montecarlo() -> None:
    """A Monte Carlo study large enough for the compiled sums, in a folder thrown away.

    Run as its own process, as a user runs it: the study's chunks may run in forked
    workers, which this process should not leave behind.
    """
    import subprocess
    import tempfile

    text = (
        'title = "precompile"\n'
        "[damper]\n"
        'damping_rate = "1.3e-4 N*m*s/rad"\n'
        'coulomb_friction = "7.9e-4 N*m"\n'
        "[gearbox]\nratio = 380\ndamping_fraction = 0.26\n"
        'coulomb_friction = "4.5e-4 N*m"\n'
        "[load]\n"
        'start_torque = "3.73 N*m"\nend_torque = "1.58 N*m"\ntravel = "1.57 rad"\n'
        'system_friction = { slope = "-0.0044 N*m/K", at_0C = "0.58 N*m" }\n'
        '[analysis]\ntemperatures = ["-40 degC", "25 degC", "100 degC"]\n'
        "[tolerances]\nseed = 1\n"
        "[tolerances.quantities]\n"
        '"damper.damping_rate" = { distribution = "normal", three_sigma = "10 %" }\n'
        '"load.start_torque" = { distribution = "normal", three_sigma = "5 %" }\n'
    )
    with tempfile.TemporaryDirectory(prefix="ecdsim-precompile-") as folder:
        config = Path(folder) / "study.toml"
        config.write_text(text, encoding="utf-8")
        args = [sys.executable, "-m", "ecdsim", "montecarlo", str(config)]
        args += ["--samples", str(MONTECARLO_SAMPLES), "--out", str(Path(folder) / "out")]
        args += ["--no-plot", "--no-progress", "--json"]
        # The notice would repeat this command's: the child stays quiet.
        env = {**os.environ, "ECDSIM_COMPILE_NOTICE": "0"}
        done = subprocess.run(args, capture_output=True, text=True, env=env, check=False)
        if done.returncode != 0:
            last = (done.stderr.strip().splitlines() or ["no message"])[-1]
            raise RuntimeError(f"the Monte Carlo study failed: {last}")


# A two-panel wing with the paper's Cc-16 ECD at both hinges: the wing's kernel is its
# own compiled entry point (ecdsim.wing.solver), which no single-hinge run reaches.
WING = """title = "precompile"
[wing.ecds.cc16.damper]
damping_rate = "1.3e-4 N*m*s/rad"
coulomb_friction = "7.9e-4 N*m"
rotor_inertia = "2e-7 kg*m^2"
[wing.ecds.cc16.gearbox]
ratio = 380
damping_fraction = 0.26
coulomb_friction = "4.5e-4 N*m"
[[wing.panels]]
mass = "1 kg"
length = "0.5 m"
cg_along = "0.25 m"
inertia = "0.0208 kg*m^2"
[[wing.panels]]
mass = "1 kg"
length = "0.5 m"
cg_along = "0.25 m"
inertia = "0.0208 kg*m^2"
[[wing.hinges]]
stowed_angle = "90 deg"
deployed_angle = "0 deg"
start_torque = "3.73 N*m"
end_torque = "1.58 N*m"
friction = { slope = "0 N*m/K", at_0C = "0.5 N*m" }
ecd = "cc16"
latch = { restitution = 0.0 }
[[wing.hinges]]
stowed_angle = "-180 deg"
deployed_angle = "0 deg"
start_torque = "3.73 N*m"
end_torque = "1.58 N*m"
friction = { slope = "0 N*m/K", at_0C = "0.5 N*m" }
ecd = "cc16"
latch = { restitution = 0.0 }
"""


def _wing() -> None:
    """A two-panel wing's deployment at +25 degC (the wing's compiled kernel)."""
    import tempfile

    from ecdsim.api import deploy_wing

    with tempfile.TemporaryDirectory(prefix="ecdsim-precompile-") as folder:
        path = Path(folder) / "wing.toml"
        path.write_text(WING, encoding="utf-8")
        deploy_wing(path, temperatures=25.0)


def workloads() -> list[Workload]:
    """The representative computations, most common first (module docstring)."""
    found = [
        Workload(
            "dynamic: roll-off and heating, one case",
            lambda: _deploy(_heating_rolloff(), [25.0]),
        ),
        Workload(
            "dynamic: roll-off and heating, 3 temperatures",
            lambda: _deploy(_heating_rolloff(), [-40.0, 25.0, 100.0]),
        ),
        Workload("dynamic: two-node heating", lambda: _deploy(_two_node(), [-40.0, 25.0, 100.0])),
        Workload(
            "dynamic: gravity, table, lost motion, Stribeck",
            lambda: _deploy(_ground_test(), [-40.0, 25.0, 100.0]),
        ),
        Workload("dynamic: lossy gear", lambda: _deploy(_lossy_gear(), [-40.0, 25.0, 100.0])),
        Workload("dynamic: compliant mesh", lambda: _deploy(_compliant_mesh(), [25.0])),
        Workload(
            "dynamic: spring table of 40 points", lambda: _deploy(_spring_table(), [-40.0, 25.0])
        ),
        Workload("wing: two panels, an ECD at each hinge", _wing),
        Workload(f"exact: a batch of {EXACT_BATCH:,} cases", _exact_batch),
    ]
    import importlib.util

    if importlib.util.find_spec("pyarrow") is not None:
        label = f"Monte Carlo: {MONTECARLO_SAMPLES:,} samples x 3 temperatures"
        found.append(Workload(label, _montecarlo, " (in its own process)"))
    return found


def precompile() -> None:
    """Compile the numerical kernels for this CPU ahead of the first run.

    About 25 s of CPU, once; later runs, and this command again, load them from the cache.
    """
    from ecdsim import _numba

    if _numba.switched_off():
        typer.echo("ECDSIM_NUMBA=0: the compiled kernels are switched off; nothing to compile")
        return
    try:
        _numba.load()
    except ImportError:
        from ecdsim.invocation import install_hint

        typer.echo(
            "numba is not installed: ecdsim runs its NumPy paths (the dynamic method about "
            f"1,000 times slower); {install_hint('numba')}",
            err=True,
        )
        raise typer.Exit(1) from None
    typer.echo("running a representative set of computations; each compiles what it needs:")
    started = time.perf_counter()
    for workload in workloads():
        before, clock = _numba.compilations(), time.perf_counter()
        try:
            workload.run()
        except Exception as exc:  # a workload that fails is a bug: say which, and stop
            typer.echo(f"error: {workload.label}: {type(exc).__name__}: {exc}", err=True)
            raise typer.Exit(1) from None
        compiled = _numba.compilations() - before
        plural = "" if compiled == 1 else "s"
        note = f" ({compiled} compilation{plural})" if compiled else workload.note
        typer.echo(f"{time.perf_counter() - clock:6.1f} s  {workload.label}{note}")
    typer.echo(
        f"done in {time.perf_counter() - started:.1f} s, {_numba.compilations()} compilations "
        "in this process; the kernels are cached in"
    )
    typer.echo(f"{_numba.cache_folder() or 'nothing (numba could not write a cache)'}")
