"""FMU export (issue 17 item 1, issue 27 items 1-3): the laws, the C damper FMU, the
deployment FMU, run by FMPy.

* the plain-float laws of the damper FMU (the physics laws the dynamic kernel compiles,
  composed by ecdsim.fmu.equations) against the paper's Eq. 1-4 by hand and against ecdsim's own
  vectorised laws (the dynamic method's eddy laws, Ecd.at, physics.thermal);
* the C translator against the Python it translates;
* the C damper FMU loaded by FMPy: its outputs and derivatives against ecdsim's laws
  to 1e-12 over speeds, temperatures, roll-off and heating; its temperature state
  integrated by the host (model exchange) and by its own RK4 (co-simulation) against
  ecdsim's heat balance integrated tightly by scipy; many instances in one process;
  FMU states; a C program as the host; a Python with FMPy and nothing of ecdsim;
* the deployment FMU against the dynamic method, its status output, many instances in
  one process, its version check; fmpy validate on every kind of export.
"""

from __future__ import annotations

import ctypes
import json
import math
import os
import shutil
import subprocess
import sys
import zipfile
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from typer.testing import CliRunner

import ecdsim
from ecdsim._types import Real
from ecdsim.cli.app import app
from ecdsim.fmu.model import DamperModel
from ecdsim.fmu.native import compiler
from ecdsim.invocation import pip_install
from ecdsim.physics import eddy as eddy_law
from ecdsim.physics import friction as friction_law
from ecdsim.physics import laws as temperature_laws
from ecdsim.physics import rolloff as rolloff_law
from ecdsim.physics import thermal
from tests import hand
from tests.conftest import require

ROOT = Path(__file__).resolve().parent.parent
PAPER = ROOT / "examples" / "paper_cc16.toml"
DYNAMIC = ROOT / "examples" / "paper_cc16_dynamic.toml"
DRIVER = ROOT / "tests" / "fmu_driver.py"
BD, C_T, N = 1.3e-4, -0.004, 380.0  # the paper's damper (section 6)
SPEEDS = (-0.3, -0.02, 0.0, 1e-4, 0.01, 0.1, 0.35, 2.0)  # slow shaft [rad/s]
TEMPERATURES = (-60.0, -40.0, 0.0, 25.0, 71.5, 100.0, 150.0)  # [degC]


def variant(folder: Path, name: str, *edits: tuple[str, str], base: Path = DYNAMIC) -> Path:
    """A copy of an example with text replaced (each old text must be there)."""
    text = base.read_text(encoding="utf-8")
    for old, new in edits:
        assert old in text, old
        text = text.replace(old, new, 1)
    path = folder / f"{name}.toml"
    path.write_text(text, encoding="utf-8")
    return path


HEATED = (
    "[gearbox]",
    '[damper.thermal]\nheat_capacity = "5 J/K"\nthermal_resistance = "20 K/W"\n\n[gearbox]',
)
HOUSING = (
    "[gearbox]",
    '[damper.thermal]\nheat_capacity = "0.4 J/K"\nthermal_resistance = "5 K/W"\n'
    'housing_heat_capacity = "3 J/K"\nhousing_thermal_resistance = "2 K/W"\n\n[gearbox]',
)
ROLLOFF = (
    "[gearbox]",
    '[damper.rolloff]\npeak_speed = "30 rad/s"\nresistivity_coefficient = "0.0039 / K"\n\n'
    "[gearbox]",
)
HOT_ROLLOFF = (
    "[gearbox]",
    '[damper.rolloff]\npeak_speed = "300 rad/s"\nresistivity_coefficient = "0.0039 / K"\n\n'
    '[damper.thermal]\nheat_capacity = "0.1 J/K"\n\n[gearbox]',
)
LOSSY = (
    'coulomb_friction = "4.5e-4 N*m"',
    'coulomb_friction = "0 N*m"\nefficiency = { forward = 0.8 }',
)
STRIBECK = (
    "static_friction_factor = 1.0",
    'static_friction_factor = 1.5\nstribeck_speed = "0.02 rad/s"',
)
TABLE = (
    'lubrication_friction = { slope = "-2.12e-6 N*m/K", at_0C = "2.2e-4 N*m" }',
    'lubrication_friction = { table = [["-50 degC", "3.4e-4 N*m"], ["0 degC", "2.2e-4 N*m"], '
    '["60 degC", "1.0e-4 N*m"], ["120 degC", "0.6e-4 N*m"]] }',
)
FRACTION_TO_RATE = ("damping_fraction = 0.26", 'damping_rate = "3.38e-5 N*m*s/rad"')


# ---- The laws in plain floats against the paper by hand and ecdsim's own laws ----------


def test_damper_model_is_the_papers_ecd_by_hand() -> None:
    model = DamperModel.from_config(ecdsim.load(PAPER))
    assert not model.heating
    for t in (-40.0, 25.0, 100.0):
        # BECD_T * u and FECD_T of Eq. 1-4 (tests/hand.py), the same sums in another
        # order: 1e-12.
        out = model.outputs(0.1, t)
        assert out["damper_torque"] == pytest.approx(hand.becd(t) * 0.1, rel=1e-12)
        assert out["coulomb_friction"] == pytest.approx(hand.fecd(t), rel=1e-12)
        assert out["friction_torque"] == pytest.approx(hand.fecd(t), rel=1e-12)
        assert model.outputs(-0.1, t)["friction_torque"] == pytest.approx(-hand.fecd(t), rel=1e-12)
        # The eddy-current power BD_T (N u)^2: the damper's share, not the gearbox's.
        power = BD * (1.0 + C_T * (t - 25.0)) * (N * 0.1) ** 2
        assert out["eddy_power"] == pytest.approx(power, rel=1e-12)
    assert model.outputs(0.0, 25.0)["friction_torque"] == 0.0
    with pytest.raises(ValueError, match="no \\[damper.thermal\\]"):
        model.derivatives(0.1, 25.0, 25.0)


def test_damper_model_with_a_lossy_mesh_by_hand(tmp_path: Path) -> None:
    # By hand: the torque is N (BD f(T) + BG) N u / eta_f (Modelica's LossyGear, forward:
    # the shaft always drives this inertia-free damper), the friction (FD + FL_T) N / eta_f
    # (Eq. 2 and 4 without FG).
    eta = 0.8
    model = DamperModel.from_config(ecdsim.load(variant(tmp_path, "lossy", LOSSY)))
    for t in (-40.0, 25.0, 100.0):
        becd = (BD * (1.0 + C_T * (t - 25.0)) + 0.26 * BD) * N**2 / eta
        fecd = (7.9e-4 + (-2.12e-6 * t + 2.2e-4)) * N / eta
        out = model.outputs(0.1, t)
        # The same sums in another order: 1e-12.
        assert out["damper_torque"] == pytest.approx(becd * 0.1, rel=1e-12)
        assert model.outputs(-0.1, t)["friction_torque"] == pytest.approx(-fecd, rel=1e-12)


def test_damper_model_with_stribeck_friction_by_hand(tmp_path: Path) -> None:
    # The ECD's share of the dynamic method's Stribeck curve, by hand:
    # FECD (1 + (f_D - 1) e^{-(u/w_St)^2}), f_D = 1.5, w_St = 0.02 rad/s.
    f_d, w_st = 1.5, 0.02
    model = DamperModel.from_config(ecdsim.load(variant(tmp_path, "stribeck", STRIBECK)))
    for t in (-40.0, 25.0, 100.0):
        assert model.outputs(0.1, t)["damper_torque"] == pytest.approx(
            hand.becd(t) * 0.1, rel=1e-12
        )
        assert model.outputs(0.1, t)["breakaway_friction"] == pytest.approx(
            f_d * hand.fecd(t), rel=1e-12
        )
        for u in (0.005, 0.02, 0.05, -0.01):
            curve = 1.0 + (f_d - 1.0) * math.exp(-((u / w_st) ** 2))
            expected = math.copysign(hand.fecd(t) * curve, u)
            assert model.outputs(u, t)["friction_torque"] == pytest.approx(expected, rel=1e-12)
    near_rest = model.outputs(1e-9, 25.0)["friction_torque"]
    assert near_rest == pytest.approx(f_d * hand.fecd(25.0), rel=1e-12)
    assert model.outputs(1.0, 25.0)["friction_torque"] == pytest.approx(hand.fecd(25.0), rel=1e-12)


def _ecdsim_laws(config: Any) -> tuple[Any, Any]:
    """ecdsim's own laws of ``config``: the dynamic method's eddy law and the ECD (Ecd)."""
    from ecdsim.deployment import build_problem
    from ecdsim.dynamics.params import DynamicParameters
    from ecdsim.dynamics.problem import dynamic_problem

    temps = np.array([25.0])
    ecd = config.system.ecd.at(temps)
    base, fs = build_problem(config.system, ecd, temps)
    damper = config.spec.damper
    params = config.spec.dynamics() or DynamicParameters(
        load_inertia=1.0,
        rolloff=damper.rolloff.to_model() if damper.rolloff else None,
        thermal=damper.thermal.to_model() if damper.thermal else None,
    )
    problem = dynamic_problem(config.system, ecd, temps, base, fs, params)
    return problem.eddy, config.system.ecd


def reference_outputs(
    config: Any, speed: float, ambient: float, damper_temp: float
) -> dict[str, float]:
    """The damper FMU's outputs by ecdsim's vectorised laws (an independent code path).

    The torque from the dynamic method's eddy law (``EddyLaw.torque_at_factor`` with its
    ``factor``, held at 0 as the dynamic method's heat balance never crosses it) and the
    ECD's BG, N and eta_f from ``Ecd.at`` (Eq. 1, 3); the friction FECD from ``Ecd.at``
    at the ambient (Eq. 2, 4).
    """
    eddy, ecd = _ecdsim_laws(config)
    state = ecd.at(np.array([ambient]))
    n = float(state.gear_ratio)
    eta = float(state.forward_efficiency)
    bg = float(state.gearbox_damping_rate)
    factor = max(float(np.ravel(eddy.factor(damper_temp))[0]), 0.0)
    shaft = n * speed
    t_eddy = float(np.ravel(eddy.torque_at_factor(shaft, factor))[0])
    fecd = float(np.ravel(state.ecd_friction)[0])
    damper = config.spec.damper
    f_d = damper.static_friction_factor
    friction = 0.0
    if speed != 0.0:
        kinetic = fecd
        if damper.stribeck_speed is not None:
            kinetic += (f_d - 1.0) * fecd * math.exp(-((speed / damper.stribeck_speed) ** 2))
        friction = math.copysign(kinetic, speed)
    return {
        "damper_torque": n * (t_eddy + bg * shaft) / eta,
        "friction_torque": friction,
        "coulomb_friction": fecd,
        "breakaway_friction": f_d * fecd,
        "eddy_power": t_eddy * shaft,
    }


def reference_rates(
    config: Any, speed: float, ambient: float, rotor: float, housing: float
) -> tuple[float, float]:
    """(dT_d/dt, dT_h/dt) by ecdsim.physics.thermal and the dynamic method's eddy law."""
    eddy, ecd = _ecdsim_laws(config)
    n = float(np.ravel(ecd.at(np.array([ambient])).gear_ratio)[0])
    factor = max(float(np.ravel(eddy.factor(rotor))[0]), 0.0)
    power = float(np.ravel(eddy.torque_at_factor(n * speed, factor))[0]) * n * speed
    spec = config.spec.damper.thermal
    r = math.inf if spec.thermal_resistance is None else spec.thermal_resistance
    if spec.housing_heat_capacity is None:
        rate = thermal.temperature_rate(power, rotor, ambient, spec.heat_capacity, r)
        return float(rate), 0.0
    r_h = math.inf if spec.housing_thermal_resistance is None else spec.housing_thermal_resistance
    rotor_rate = thermal.temperature_rate(power, rotor, housing, spec.heat_capacity, r)
    shell = thermal.housing_rate(
        rotor - ambient, housing - ambient, spec.housing_heat_capacity, r, r_h
    )
    return float(rotor_rate), float(shell)


CASES: dict[str, tuple[tuple[str, str], ...]] = {
    "linear": (),
    "rolloff": (ROLLOFF,),
    "lossy": (LOSSY,),
    "stribeck": (STRIBECK,),
    "table": (TABLE,),
    "bg_rate": (FRACTION_TO_RATE,),
    "heated": (HEATED,),
    "housing": (HOUSING,),
    "hot_rolloff": (HOT_ROLLOFF,),
}


def _close(got: float, expected: float, scale: float) -> bool:
    # 1e-12 of the quantity's scale: the two paths order their sums and products
    # differently (a few roundings), far below this.
    return abs(got - expected) <= 1e-12 * scale


@pytest.mark.parametrize("case", sorted(CASES))
def test_plain_laws_equal_ecdsims_vectorised_laws(tmp_path: Path, case: str) -> None:
    config = ecdsim.load(variant(tmp_path, case, *CASES[case]))
    model = DamperModel.from_config(config)
    for speed in SPEEDS:
        for ambient in TEMPERATURES:
            for rise in (0.0, 7.5, 180.0) if model.heating else (0.0,):
                got = model.outputs(speed, ambient, ambient + rise if model.heating else None)
                want = reference_outputs(config, speed, ambient, ambient + rise)
                for name, value in want.items():
                    scale = max(abs(value), abs(want["coulomb_friction"]), 1e-3)
                    assert _close(got[name], value, scale), (name, speed, ambient, rise)
                if model.heating:
                    housing = ambient + 0.4 * rise
                    rates = model.derivatives(speed, ambient, ambient + rise, housing)
                    expected = reference_rates(config, speed, ambient, ambient + rise, housing)
                    for g, e in zip(rates, expected, strict=True):
                        assert _close(g, e, max(abs(e), 1e-3)), (speed, ambient, rise)


def test_the_factor_is_held_at_the_laws_zero() -> None:
    # Beyond T_zero = T_ref - 1/c the linear law's factor would be negative (a damper that
    # drives); held at 0, as the dynamic method never crosses it (docs/dynamics.md).
    assert eddy_law.temperature_factor(275.0 + 1e-9, 25.0, -0.004) == 0.0
    assert eddy_law.temperature_factor(-40.0, 25.0, -0.004) == pytest.approx(1.26, rel=1e-15)


# ---- The C translator -----------------------------------------------------------------


def _compile(tmp_path: Path, source: str, name: str) -> ctypes.CDLL:
    c_file = tmp_path / f"{name}.c"
    c_file.write_text("#include <math.h>\n" + source, encoding="utf-8")
    library = tmp_path / f"{name}.so"
    subprocess.run(
        [
            *compiler(),
            "-shared",
            "-fPIC",
            "-O2",
            "-std=c99",
            "-ffp-contract=off",
            "-Wall",
            "-Werror",
            "-o",
            str(library),
            str(c_file),
            "-lm",
        ],
        check=True,
        capture_output=True,
    )
    return ctypes.CDLL(str(library))


def _exported(functions: list[Callable[..., Any]]) -> str:
    """The translation of ``functions`` with a non-static wrapper per function."""
    import inspect
    import typing

    from ecdsim.fmu import ctranslate

    out = [ctranslate.translate(functions)]
    for f in functions:
        hints = typing.get_type_hints(f)
        names = list(inspect.signature(f).parameters)
        kinds = {float: "double", int: "int", bool: "int"}
        kind = {
            n: "double" if hints[n] == Real else kinds.get(hints[n], "const double *")
            for n in names
        }
        args = ", ".join(f"{kind[n]} {n}" for n in names)
        call = f"ecd_{f.__name__}({', '.join(names)})"
        out.append(f"double py_{f.__name__}({args}) {{ return (double){call}; }}")
    return "\n".join(out)


def test_translated_laws_equal_the_python(tmp_path: Path) -> None:
    # Every law of the damper FMU, translated and compiled, against the Python function
    # on random arguments (and special values). The same IEEE operations in the same
    # order, libm's functions as CPython's: 1e-15 allows a libm of another build.
    laws: list[Callable[..., Any]] = [
        eddy_law.temperature_factor,
        eddy_law.linear_eddy_torque,
        rolloff_law.kloss_torque,
        eddy_law.slow_shaft_damping_torque,
        temperature_laws.linear_law,
        friction_law.input_coulomb_friction,
        friction_law.stribeck_friction,
        thermal.heat_loss,
        thermal.temperature_rate,
    ]
    library = _compile(tmp_path, _exported(laws), "laws")
    rng = np.random.default_rng(27)
    specials = [0.0, -0.0, 1.0, -1.0, math.inf, 1e-300, 1e300]
    for law in laws:
        import inspect

        arity = len(inspect.signature(law).parameters)
        c_function = getattr(library, f"py_{law.__name__}")
        c_function.restype = ctypes.c_double
        c_function.argtypes = [ctypes.c_double] * arity
        for k in range(300):
            if k < len(specials):
                args = [specials[k]] + list(rng.uniform(0.1, 10.0, arity - 1))
            else:
                args = list(rng.uniform(-500.0, 500.0, arity))
            args = [float(a) for a in args]
            try:
                expected = law(*args)
            except (ZeroDivisionError, OverflowError):
                continue  # Python raises where C gives inf or NaN (ctranslate's docstring)
            got = c_function(*args)
            if math.isnan(expected):
                assert math.isnan(got), (law.__name__, args)
            else:
                assert got == pytest.approx(expected, rel=1e-15, abs=0.0), (law.__name__, args)


def test_translated_table_and_eddy_law_equal_the_python(tmp_path: Path) -> None:
    library = _compile(
        tmp_path,
        _exported([temperature_laws.table_in_temperature, eddy_law.rated_eddy_torque]),
        "table",
    )
    table = library.py_table_in_temperature
    table.restype = ctypes.c_double
    array = ctypes.c_double * 4
    temps, values = [-50.0, 0.0, 60.0, 120.0], [3.4e-4, 2.2e-4, 1.0e-4, 0.6e-4]
    table.argtypes = [ctypes.c_double, array, array, ctypes.c_int]
    for t in np.linspace(-80.0, 150.0, 93):
        expected = temperature_laws.table_in_temperature(float(t), temps, values, 4)
        # np.interp, NumPy's own piecewise-linear interpolation, held at the ends.
        assert expected == pytest.approx(float(np.interp(t, temps, values)), rel=1e-14)
        assert table(float(t), array(*temps), array(*values), 4) == pytest.approx(
            expected, rel=1e-15
        )
    eddy = library.py_rated_eddy_torque
    eddy.restype = ctypes.c_double
    eddy.argtypes = [ctypes.c_double] * 4 + [ctypes.c_int]
    for w in (-400.0, 0.0, 3.0, 30.0, 1e4):
        for rolloff in (False, True):
            expected = eddy_law.rated_eddy_torque(w, 0.9, 1.3e-4, 30.0, rolloff)
            assert eddy(w, 0.9, 1.3e-4, 30.0, int(rolloff)) == pytest.approx(expected, rel=1e-15)


def test_the_translator_refuses_what_it_does_not_translate() -> None:
    from ecdsim.fmu import ctranslate

    def uses_a_list(x: float) -> float:
        values = [x, x]
        return values[0]

    def unannotated(x):  # type: ignore[no-untyped-def]
        return x

    def floor_division(x: float) -> float:
        return x // 2.0

    def reserved(double: float) -> float:
        return double

    for function, message in (
        (uses_a_list, "List is not translated"),
        (unannotated, "annotate x, return"),
        (floor_division, "FloorDiv is not translated"),
        (reserved, "reserved in C"),
    ):
        with pytest.raises(ctranslate.TranslationError, match=message) as caught:
            ctranslate.translate([function])
        assert function.__name__ in str(caught.value)  # names the function


def test_the_translation_keeps_pythons_arithmetic(tmp_path: Path) -> None:
    # True division of ints, ** as pow, min/max as Python's, loops, int locals, module
    # constants and math.pi.
    def arithmetic2(a: float, n: int) -> float:
        total = 0.0
        for i in range(n):
            total += (i + 1) / 2 + a**2
        k = n if a > 0.0 else -n
        return max(total, -a) + min(a, 0.0) - k / 4 + N * math.pi  # a module constant

    library = _compile(tmp_path, _exported([arithmetic2]), "arith")
    function = library.py_arithmetic2
    function.restype = ctypes.c_double
    function.argtypes = [ctypes.c_double, ctypes.c_int]
    for a in (-3.5, 0.0, 0.25, 7.0):
        for n in (0, 1, 5):
            assert function(a, n) == pytest.approx(arithmetic2(a, n), rel=1e-15)


# ---- The C damper FMU -----------------------------------------------------------------


def export(config: Path, out: Path, *options: str) -> Path:
    result = CliRunner().invoke(app, ["export-fmu", str(config), "-o", str(out), *options])
    assert result.exit_code == 0, result.output
    return out


class Loaded:
    """A C damper FMU loaded in this process by FMPy (model exchange or co-simulation)."""

    def __init__(
        self, fmu: Path, folder: Path, kind: str = "cs", name: str = "test", callbacks: Any = None
    ) -> None:
        import fmpy
        from fmpy.fmi2 import FMU2Model, FMU2Slave

        self.md = fmpy.read_model_description(str(fmu))
        self.refs = {v.name: v.valueReference for v in self.md.modelVariables}
        unzipped = folder / "unzipped"
        if not unzipped.exists():
            fmpy.extract(str(fmu), unzipdir=str(unzipped))
        cls, ident = (
            (FMU2Slave, self.md.coSimulation)
            if kind == "cs"
            else (
                FMU2Model,
                self.md.modelExchange,
            )
        )
        self.fmu = cls(
            guid=self.md.guid,
            unzipDirectory=str(unzipped),
            modelIdentifier=ident.modelIdentifier,
            instanceName=name,
        )
        self.fmu.instantiate(callbacks=callbacks)

    def start(self, **values: float) -> Loaded:
        self.fmu.setupExperiment(startTime=0.0)
        self.fmu.enterInitializationMode()
        if values:
            self.set(**values)
        self.fmu.exitInitializationMode()
        return self

    def set(self, **values: float) -> None:
        self.fmu.setReal([self.refs[n] for n in values], [float(v) for v in values.values()])

    def get(self, *names: str) -> list[float]:
        return list(self.fmu.getReal([self.refs[n] for n in names]))

    def free(self) -> None:
        self.fmu.terminate()
        self.fmu.freeInstance()


@pytest.fixture(scope="module")
def fmus(tmp_path_factory: pytest.TempPathFactory) -> dict[str, tuple[Path, Any]]:
    """One C damper FMU per case of CASES (compiled once for the module)."""
    require("fmpy")
    folder = tmp_path_factory.mktemp("fmus")
    built = {}
    for case, edits in CASES.items():
        config = variant(folder, case, *edits)
        built[case] = (export(config, folder / f"{case}.fmu"), ecdsim.load(config))
    return built


@pytest.mark.parametrize("case", sorted(CASES))
def test_c_damper_fmu_equals_ecdsims_laws(
    fmus: dict[str, tuple[Path, Any]], tmp_path: Path, case: str
) -> None:
    # The FMU's outputs (co-simulation) and derivatives (model exchange, the host setting
    # the states) against ecdsim's vectorised laws, to 1e-12 of each quantity's scale,
    # over speeds, ambient and damper temperatures (to 180 K above ambient, past the
    # linear law's zero at 275 degC: the factor held at 0 as in ecdsim).
    fmu, config = fmus[case]
    model = DamperModel.from_config(config)
    cs = Loaded(fmu, tmp_path, "cs").start()
    me = Loaded(fmu, tmp_path, "me", "me").start()
    outputs = list(reference_outputs(config, 0.1, 25.0, 25.0))
    states = ["damper_temperature", "housing_temperature"][: me.md.numberOfContinuousStates]
    for speed in SPEEDS:
        for ambient in TEMPERATURES:
            for rise in (0.0, 7.5, 180.0) if model.heating else (0.0,):
                cs.set(shaft_speed=speed, ambient_temperature=ambient)
                me.set(shaft_speed=speed, ambient_temperature=ambient)
                damper_temp = ambient + rise
                housing = ambient + 0.4 * rise
                if states:
                    me.fmu.setContinuousStates(
                        (ctypes.c_double * len(states))(*[damper_temp, housing][: len(states)]),
                        len(states),
                    )
                want = reference_outputs(config, speed, ambient, damper_temp)
                got = dict(zip(outputs, me.get(*outputs), strict=True))
                for name, value in want.items():
                    scale = max(abs(value), abs(want["coulomb_friction"]), 1e-3)
                    assert _close(got[name], value, scale), (case, name, speed, ambient, rise)
                if not states:  # without heating, co-simulation gives the same outputs
                    got_cs = dict(zip(outputs, cs.get(*outputs), strict=True))
                    assert got_cs == got
                if states:
                    derivatives = (ctypes.c_double * len(states))()
                    me.fmu.getDerivatives(derivatives, len(states))
                    expected = reference_rates(config, speed, ambient, damper_temp, housing)
                    for g, e in zip(derivatives, expected, strict=False):
                        assert _close(g, e, max(abs(e), 1e-3)), (case, speed, ambient, rise)
    cs.free()
    me.free()


def test_c_damper_fmus_pass_fmpy_validate_and_declare_units(
    fmus: dict[str, tuple[Path, Any]],
) -> None:
    import fmpy
    from fmpy.validation import validate_fmu

    for case, (fmu, config) in fmus.items():
        assert validate_fmu(str(fmu)) == [], case
        md = fmpy.read_model_description(str(fmu))
        units = {u.name: u for u in md.unitDefinitions}
        assert units["degC"].baseUnit.K == 1
        assert units["degC"].baseUnit.offset == 273.15
        for v in md.modelVariables:
            dimensionless = ("ratio" in v.name or "factor" in v.name) or v.name in (
                "forward_efficiency",
                "gearbox_damping_fraction",
            )
            if v.type == "Real" and not dimensionless:
                assert v.unit in units, (case, v.name)
        byname = {v.name: v for v in md.modelVariables}
        assert byname["ambient_temperature"].unit == "degC"
        assert byname["damper_torque"].unit == "N.m"
        # Both interfaces, one library; no Python needed; a DefaultExperiment past the
        # slowest deployment of the config's analysis temperatures (exact method).
        assert md.modelExchange.modelIdentifier == md.coSimulation.modelIdentifier
        slowest = max(ecdsim.deploy(config, methods="exact").deployment_time("exact").values())
        assert slowest < float(md.defaultExperiment.stopTime) < 1.25 * slowest
        heating = config.spec.damper.thermal is not None
        assert md.numberOfContinuousStates == (
            0 if not heating else 2 if config.spec.damper.thermal.housing_heat_capacity else 1
        )
    identifiers = {
        fmpy.read_model_description(str(f)).coSimulation.modelIdentifier for f, _ in fmus.values()
    }
    assert len(identifiers) == len(fmus)  # a unique model identifier per export


def _heated_reference(
    config: Any, times: np.ndarray, speed: Callable[[float], float], ambient: float
) -> np.ndarray:
    """ecdsim's own heat balance integrated tightly: the dynamic method's log state.

    ``s' = (p - (T - T_amb) / (R f)) / C`` in the damping factor's logarithm
    (ecdsim.physics.thermal.factor_log_rate, the form the dynamic core integrates; a
    different formulation from the FMU's, which integrates T), by scipy's DOP853 at
    rtol 1e-12, T recovered by thermal.temperature_from_factor_log.
    """
    from scipy.integrate import solve_ivp

    eddy, ecd = _ecdsim_laws(config)
    n = float(np.ravel(ecd.at(np.array([ambient])).gear_ratio)[0])
    spec = config.spec.damper.thermal
    r = math.inf if spec.thermal_resistance is None else spec.thermal_resistance
    c = float(np.ravel(eddy.coefficient)[0])
    f_a = float(np.ravel(eddy.factor(ambient))[0])
    a, b, core = (float(np.ravel(v)[0]) for v in eddy.parameters)

    def rate(t: float, y: np.ndarray) -> list[float]:
        shaft = n * speed(t)
        f = float(thermal.damping_factor_from_log(y[0], f_a, c))
        # The eddy power over f of the law the kernel compiles (physics.eddy).
        p = float(eddy_law.eddy_torque_parts(eddy.code, a, b, core, shaft, f)[3])
        return [float(thermal.factor_log_rate(p, y[0], spec.heat_capacity, r, c))]

    solution = solve_ivp(
        rate, (times[0], times[-1]), [0.0], method="DOP853", rtol=1e-12, atol=1e-14, t_eval=times
    )
    assert solution.success
    return np.asarray(thermal.temperature_from_factor_log(solution.y[0], ambient, f_a, c))


def test_model_exchange_the_host_integrates_the_heat_state(tmp_path: Path) -> None:
    # The host (here scipy's DOP853 at rtol 1e-12, calling fmi2SetContinuousStates and
    # fmi2GetDerivatives) integrates the FMU's temperature state; ecdsim's heat balance
    # integrated alike in its own log-state form must agree to the integrators'
    # tolerance. A speed that varies (a ramp and a sine) and a damper that heats by tens
    # of kelvin, with roll-off: the factor and the Kloss law matter.
    from scipy.integrate import solve_ivp

    require("fmpy")
    config_path = variant(tmp_path, "hot", HOT_ROLLOFF)
    config = ecdsim.load(config_path)
    fmu = export(config_path, tmp_path / "hot.fmu")
    me = Loaded(fmu, tmp_path, "me").start(ambient_temperature=-40.0)

    def speed(t: float) -> float:
        return 0.05 + 0.02 * t + 0.03 * math.sin(3.0 * t)

    def rate(t: float, y: np.ndarray) -> list[float]:
        me.set(shaft_speed=speed(t))
        me.fmu.setTime(t)
        me.fmu.setContinuousStates((ctypes.c_double * 1)(y[0]), 1)
        out = (ctypes.c_double * 1)()
        me.fmu.getDerivatives(out, 1)
        return [out[0]]

    times = np.linspace(0.0, 8.0, 81)
    host = solve_ivp(
        rate, (0.0, 8.0), [-40.0], method="DOP853", rtol=1e-12, atol=1e-12, t_eval=times
    )
    me.free()
    reference = _heated_reference(config, times, speed, -40.0)
    assert reference[-1] - reference[0] > 20.0  # heats: the factor changes the power
    # Two integrations at rtol 1e-12 of a rise of tens of kelvin: 1e-9 K.
    assert np.max(np.abs(host.y[0] - reference)) < 1e-9


def test_model_exchange_with_fmpys_cvode(tmp_path: Path) -> None:
    # FMPy's own model-exchange host (CVode, rtol 1e-10) integrates the two-node heat
    # state; ecdsim's balance integrated by scipy at rtol 1e-12 (physics.thermal through
    # DamperModel's plain laws would be the FMU's own code: this uses the vectorised
    # reference_rates) agrees to CVode's tolerance.
    from scipy.integrate import solve_ivp

    fmpy = require("fmpy")
    config_path = variant(tmp_path, "housing", HOUSING)
    config = ecdsim.load(config_path)
    fmu = export(config_path, tmp_path / "housing.fmu")
    signal = np.array(
        [(0.0, 0.12, 10.0), (30.0, 0.12, 10.0)],
        dtype=[("time", float), ("shaft_speed", float), ("ambient_temperature", float)],
    )
    result = fmpy.simulate_fmu(
        str(fmu),
        fmi_type="ModelExchange",
        stop_time=30.0,
        input=signal,
        output_interval=1.0,
        relative_tolerance=1e-10,
        output=["damper_temperature", "housing_temperature"],
    )

    def rate(t: float, y: np.ndarray) -> list[float]:
        return list(reference_rates(config, 0.12, 10.0, y[0], y[1]))

    reference = solve_ivp(
        rate,
        (0.0, 30.0),
        [10.0, 10.0],
        method="DOP853",
        rtol=1e-12,
        atol=1e-12,
        t_eval=result["time"],
    )
    assert reference.y[0, -1] - 10.0 > 1.0  # the rotor heats by kelvins
    # CVode at rtol 1e-10 (absolute 1e-10 x the nominal 100 K): 1e-6 K.
    assert np.max(np.abs(result["damper_temperature"] - reference.y[0])) < 1e-6
    assert np.max(np.abs(result["housing_temperature"] - reference.y[1])) < 1e-6


def test_co_simulation_rk4_against_a_tight_integration(tmp_path: Path) -> None:
    # The FMU's own integrator in co-simulation: RK4 in substeps of at most max_step,
    # the input speed extrapolated linearly from the last two communication points.
    # Against ecdsim's heat balance integrated tightly (DOP853, rtol 1e-12) with the
    # speed the host's samples define (piecewise linear): with communication steps of
    # 0.1 s and max_step 1 ms the RK4 error is below 1e-9 K; fourth order: halving
    # max_step divides the error by about 16.
    require("fmpy")
    config_path = variant(tmp_path, "hot", HOT_ROLLOFF)
    config = ecdsim.load(config_path)
    fmu = export(config_path, tmp_path / "hot.fmu")
    times = np.linspace(0.0, 6.0, 61)

    def speed(t: float) -> float:
        return 0.05 + 0.02 * t + 0.03 * math.sin(3.0 * t)

    samples = np.array([speed(t) for t in times])

    def piecewise(t: float, k: int) -> float:
        # What extrapolation from the last two samples makes of the samples: over
        # [t_k, t_k+1] the line through (t_k-1, u_k-1) and (t_k, u_k) (held in the first).
        if k == 0:
            return float(samples[0])
        slope = (samples[k] - samples[k - 1]) / 0.1
        return float(samples[k] + slope * (t - times[k]))

    def run(max_step: float) -> np.ndarray:
        cs = Loaded(fmu, tmp_path, "cs", f"rk4_{max_step}").start(
            ambient_temperature=-40.0, max_step=max_step
        )
        got = []
        for k, t in enumerate(times):
            cs.set(shaft_speed=float(samples[k]))
            got.append(cs.get("damper_temperature")[0])
            if k + 1 < len(times):
                cs.fmu.doStep(float(t), 0.1)
        cs.free()
        return np.array(got)

    from scipy.integrate import solve_ivp

    eddy, _ = _ecdsim_laws(config)
    spec = config.spec.damper.thermal
    assert spec is not None

    def rate(t: float, y: np.ndarray, k: int) -> list[float]:
        shaft = N * piecewise(t, k)
        factor = max(float(np.ravel(eddy.factor(y[0]))[0]), 0.0)
        power = float(np.ravel(eddy.torque_at_factor(shaft, factor))[0]) * shaft
        return [float(thermal.temperature_rate(power, y[0], -40.0, spec.heat_capacity, math.inf))]

    reference = np.empty_like(times)
    reference[0] = y = -40.0
    for k in range(len(times) - 1):  # piece by piece: the speed bends at each sample
        step = solve_ivp(
            rate, (times[k], times[k + 1]), [y], method="DOP853", rtol=1e-13, atol=1e-13, args=(k,)
        )
        y = float(step.y[0, -1])
        reference[k + 1] = y
    assert reference[-1] - reference[0] > 10.0
    assert np.max(np.abs(run(1e-3) - reference)) < 1e-9
    error_coarse = np.max(np.abs(run(0.1) - reference))
    error_half = np.max(np.abs(run(0.05) - reference))
    assert error_coarse > 1e-9  # the integrator's own error, well above the reference's
    assert 12.0 < error_coarse / error_half < 20.0  # fourth order: 2^4 = 16


def test_co_simulation_matches_the_adiabatic_closed_form(tmp_path: Path) -> None:
    # An adiabatic damper (no thermal_resistance) at a constant speed: C dT/dt =
    # BD f(T) (N u)^2 with f = 1 + c (T - 25), so f(t) = exp(c k t), k = BD (N u)^2 / C,
    # and T = 25 + (f - 1) / c, by hand. The FMU's RK4 (1 ms) over 10 s of 1 s steps.
    require("fmpy")
    config = variant(
        tmp_path,
        "adiabatic",
        ("[gearbox]", '[damper.thermal]\nheat_capacity = "0.05 J/K"\n\n[gearbox]'),
    )
    fmu = export(config, tmp_path / "adiabatic.fmu")
    u = 0.1  # slow shaft [rad/s]
    cs = Loaded(fmu, tmp_path, "cs").start(ambient_temperature=25.0)
    cs.set(shaft_speed=u)
    for k in range(10):
        cs.fmu.doStep(float(k), 1.0)
    temperature = cs.get("damper_temperature")[0]
    cs.free()
    k_rate = BD * (N * u) ** 2 / 0.05
    expected = 25.0 + (math.exp(C_T * k_rate * 10.0) - 1.0) / C_T
    assert expected - 25.0 > 30.0  # a real rise, so that the factor matters
    # RK4 with 1 ms steps on a smooth exponential: far below 1e-9 K.
    assert temperature == pytest.approx(expected, abs=1e-9)


def test_damper_fmu_reproduces_a_dynamic_run(tmp_path: Path) -> None:
    # Driven with the speed history of an ecdsim dynamic run (2 ms steps), the FMU's
    # damper temperature and torque are the run's: ecdsim's own heat balance, integrated
    # by the dynamic core.
    require("fmpy")
    from ecdsim.plotting_dynamic import dynamic_result

    config = variant(tmp_path, "heated", HEATED)
    fmu = export(config, tmp_path / "damper.fmu")
    ambient = 25.0
    run = ecdsim.deploy(config, temperatures=ambient, methods="dynamic")
    result = dynamic_result(run.prediction)
    assert result is not None
    latch = run.deployment_time("dynamic")[ambient]
    step = 2e-3
    times = np.arange(0.0, latch, step)
    series = result.sample(times)
    speed = series.speed[:, 0]
    heat = series.damper_temperature[:, 0]
    torque = -series.damping_torque[:, 0]  # the run's, opposing the motion
    assert heat[-1] - ambient > 0.3  # the damper heats: the check has something to see
    cs = Loaded(fmu, tmp_path, "cs").start(ambient_temperature=ambient)
    got = []
    for k, t in enumerate(times):
        cs.set(shaft_speed=float(speed[k]))
        got.append(cs.get("damper_temperature", "damper_torque", "friction_torque"))
        if k + 1 < len(times):
            cs.fmu.doStep(float(t), step)
    cs.free()
    table = np.array(got)
    # 1e-6: the FMU integrates the heat balance with the speed extrapolated over each
    # 2 ms step from the last two inputs (error ~ step^2, about 4e-7 K here); the run's
    # own tolerance (rtol 1e-8) is far below.
    assert np.max(np.abs(table[:, 0] - heat)) < 1e-6
    moving = np.abs(torque) > 0.0
    assert np.max(np.abs(table[moving, 1] / torque[moving] - 1.0)) < 1e-6
    # The same torque by hand from the run's speed and damper temperature (Eq. 1, 3).
    by_hand = N**2 * (BD * (1.0 + C_T * (heat - 25.0)) + 0.26 * BD) * speed
    assert np.max(np.abs(table[moving, 1] / by_hand[moving] - 1.0)) < 1e-6
    friction = table[moving, 2]
    assert friction == pytest.approx(np.full(friction.size, hand.fecd(25.0)), rel=1e-12)


def test_many_instances_each_with_its_own_state(tmp_path: Path) -> None:
    # Three live instances of one FMU in this process, stepped in turn with different
    # speeds and ambient temperatures, each equal to the same instance run alone; the
    # FMU's state saved, restored and serialised.
    require("fmpy")
    fmu = export(variant(tmp_path, "heated", HEATED), tmp_path / "heated.fmu")
    speeds = (0.05, 0.2, 0.4)
    ambients = (-40.0, 25.0, 100.0)

    def step_all(instances: list[Loaded], which: list[int], count: int) -> list[list[float]]:
        got: list[list[float]] = [[] for _ in instances]
        for k in range(count):
            for i, inst in enumerate(instances):
                inst.set(shaft_speed=speeds[which[i]] * (1.0 + 0.1 * k))
                got[i].append(inst.get("damper_temperature", "damper_torque")[0])
                inst.fmu.doStep(0.05 * k, 0.05)
        return got

    together = [
        Loaded(fmu, tmp_path, "cs", f"i{i}").start(ambient_temperature=ambients[i])
        for i in range(3)
    ]
    both = step_all(together, [0, 1, 2], 40)
    state = together[0].fmu.getFMUstate()
    saved = together[0].fmu.serializeFMUstate(state)
    before = together[0].get("damper_temperature")
    together[0].fmu.doStep(2.0, 1.0)
    assert together[0].get("damper_temperature") != before
    together[0].fmu.setFMUstate(state)
    assert together[0].get("damper_temperature") == before
    together[0].fmu.doStep(2.0, 1.0)
    restored = together[0].fmu.deSerializeFMUstate(saved)
    together[0].fmu.setFMUstate(restored)
    assert together[0].get("damper_temperature") == before
    together[0].fmu.freeFMUstate(state)
    together[0].fmu.freeFMUstate(restored)
    for inst in together:
        inst.free()
    for i in range(3):
        alone = Loaded(fmu, tmp_path, "cs", f"alone{i}").start(ambient_temperature=ambients[i])
        assert step_all([alone], [i], 40)[0] == both[i]
        alone.free()
    assert len({round(b[-1], 6) for b in both}) == 3  # three different histories


def test_the_fmu_refuses_what_fmi_forbids(tmp_path: Path) -> None:
    # A fixed parameter after initialisation, an output, a value outside its range: an
    # error status with a message naming the variable, and the instance unchanged.
    require("fmpy")
    from fmpy.fmi1 import FMICallException

    fmu = export(variant(tmp_path, "heated", HEATED), tmp_path / "heated.fmu")
    messages: list[str] = []
    from fmpy.fmi2 import (
        fmi2CallbackAllocateMemoryTYPE,
        fmi2CallbackFreeMemoryTYPE,
        fmi2CallbackFunctions,
        fmi2CallbackLoggerTYPE,
    )
    from fmpy.simulation import calloc, free

    def logger(env: Any, name: bytes, status: int, category: bytes, message: bytes) -> None:
        messages.append(message.decode())

    callbacks = fmi2CallbackFunctions()
    callbacks.logger = fmi2CallbackLoggerTYPE(logger)
    callbacks.allocateMemory = fmi2CallbackAllocateMemoryTYPE(calloc)
    callbacks.freeMemory = fmi2CallbackFreeMemoryTYPE(free)
    cs = Loaded(fmu, tmp_path, "cs", callbacks=callbacks).start()
    with pytest.raises(FMICallException):
        cs.set(gear_ratio=400.0)
    assert "gear_ratio is a fixed parameter" in messages[-1]
    with pytest.raises(FMICallException):
        cs.set(damper_torque=1.0)
    assert "damper_torque is not an input or a parameter" in messages[-1]
    with pytest.raises(FMICallException):
        cs.set(ambient_temperature=-300.0)
    assert "ambient_temperature = -300 is outside its range" in messages[-1]
    assert cs.get("gear_ratio", "ambient_temperature") == [380.0, -40.0]
    cs.free()
    cs2 = Loaded(fmu, tmp_path, "cs", "c2")
    cs2.fmu.setupExperiment(startTime=0.0)
    cs2.fmu.enterInitializationMode()
    with pytest.raises(FMICallException):
        cs2.set(heat_capacity=0.0)  # > 0: the balance divides by it
    cs2.fmu.freeInstance()


C_HOST = r"""
/* A minimal FMI 2.0 co-simulation host in C: no Python anywhere in this process. */
#include <dlfcn.h>
#include <stdio.h>
#include <stdlib.h>
typedef void *C;
typedef struct {
  void (*logger)(void *, const char *, int, const char *, const char *, ...);
  void *(*alloc)(size_t, size_t);
  void (*free)(void *);
  void *step;
  void *env;
} Callbacks;
typedef C (*Instantiate)(const char *, int, const char *, const char *, const Callbacks *,
                         int, int);
typedef int (*Setup)(C, int, double, double, int, double);
typedef int (*Mode)(C);
typedef int (*SetReal)(C, const unsigned *, size_t, const double *);
typedef int (*GetReal)(C, const unsigned *, size_t, double *);
typedef int (*DoStep)(C, double, double, int);
typedef void (*Free)(C);
static void logger(void *e, const char *n, int s, const char *c, const char *m, ...) {
  (void)e; (void)s; (void)c; fprintf(stderr, "%s: %s\n", n, m);
}
int main(int argc, char **argv) {
  void *lib = dlopen(argv[1], RTLD_NOW | RTLD_LOCAL);
  if (argc != 9) return 2;
  if (!lib) { fprintf(stderr, "%s\n", dlerror()); return 3; }
  Instantiate inst = (Instantiate)dlsym(lib, "fmi2Instantiate");
  Setup setup = (Setup)dlsym(lib, "fmi2SetupExperiment");
  Mode enter = (Mode)dlsym(lib, "fmi2EnterInitializationMode");
  Mode leave = (Mode)dlsym(lib, "fmi2ExitInitializationMode");
  SetReal setr = (SetReal)dlsym(lib, "fmi2SetReal");
  GetReal getr = (GetReal)dlsym(lib, "fmi2GetReal");
  DoStep step = (DoStep)dlsym(lib, "fmi2DoStep");
  Free freei = (Free)dlsym(lib, "fmi2FreeInstance");
  Callbacks cb = {logger, calloc, free, NULL, NULL};
  unsigned speed = (unsigned)atoi(argv[3]), ambient = (unsigned)atoi(argv[4]);
  unsigned out[2] = {(unsigned)atoi(argv[5]), (unsigned)atoi(argv[6])};
  double values[2], u = atof(argv[7]), t_amb = atof(argv[8]);
  C c = inst("c-host", 1, argv[2], "", &cb, 0, 0);
  if (!c) return 4;
  if (setup(c, 0, 0.0, 0.0, 0, 0.0) || enter(c)) return 5;
  if (setr(c, &ambient, 1, &t_amb) || leave(c)) return 5;
  for (int k = 0; k < 100; k++) {
    if (setr(c, &speed, 1, &u) || step(c, 0.01 * k, 0.01, 1)) return 6;
  }
  if (getr(c, out, 2, values)) return 7;
  printf("%.17g %.17g\n", values[0], values[1]);
  freei(c);
  return 0;
}
"""


def test_a_c_program_hosts_the_damper_fmu(tmp_path: Path) -> None:
    # The shared library loads into a C program (dlopen, no Python in the process) and
    # runs: 1 s at 0.2 rad/s from -40 degC. Against ecdsim's heat balance integrated by
    # scipy (rtol 1e-12): the FMU's RK4 at 1 ms, 1e-9 K.
    fmpy = require("fmpy")
    from scipy.integrate import solve_ivp

    config_path = variant(tmp_path, "heated", HOT_ROLLOFF)
    fmu = export(config_path, tmp_path / "heated.fmu")
    md = fmpy.read_model_description(str(fmu))
    refs = {v.name: v.valueReference for v in md.modelVariables}
    with zipfile.ZipFile(fmu) as archive:
        archive.extractall(tmp_path / "x")
    library = tmp_path / "x" / "binaries" / "linux64" / f"{md.coSimulation.modelIdentifier}.so"
    host = tmp_path / "host"
    (tmp_path / "host.c").write_text(C_HOST, encoding="utf-8")
    subprocess.run(
        [*compiler(), "-std=c99", "-o", str(host), str(tmp_path / "host.c"), "-ldl"], check=True
    )
    done = subprocess.run(
        [
            str(host),
            str(library),
            md.guid,
            str(refs["shaft_speed"]),
            str(refs["ambient_temperature"]),
            str(refs["damper_temperature"]),
            str(refs["damper_torque"]),
            "0.2",
            "-40",
        ],
        capture_output=True,
        text=True,
        check=False,
    )
    assert done.returncode == 0, done.stderr
    temperature, torque = (float(v) for v in done.stdout.split())
    config = ecdsim.load(config_path)
    reference = solve_ivp(
        lambda t, y: [reference_rates(config, 0.2, -40.0, y[0], -40.0)[0]],
        (0.0, 1.0),
        [-40.0],
        method="DOP853",
        rtol=1e-12,
        atol=1e-12,
    )
    assert reference.y[0, -1] + 40.0 > 5.0
    assert temperature == pytest.approx(reference.y[0, -1], abs=1e-9)
    want = reference_outputs(config, 0.2, -40.0, temperature)["damper_torque"]
    assert torque == pytest.approx(want, rel=1e-12)


# ---- A Python with FMPy and nothing of ecdsim -------------------------------------------


@pytest.fixture(scope="session")
def clean_python() -> Path:
    """A venv with FMPy (the test environment's version) and nothing of ecdsim.

    Made once and kept beside the test venv (``.venv/fmu-host-fmpy-<version>``; ``make
    clean`` removes it), so later runs reuse it.
    """
    fmpy = require("fmpy")
    folder = Path(sys.prefix) / f"fmu-host-fmpy-{fmpy.__version__}"
    python = folder / "bin" / "python"
    done = folder / ".complete"
    if not done.exists():
        shutil.rmtree(folder, ignore_errors=True)
        subprocess.run([sys.executable, "-m", "venv", str(folder)], check=True)
        subprocess.run(
            [str(python), "-m", "pip", "install", "--quiet", f"fmpy=={fmpy.__version__}"],
            check=True,
            timeout=900,
        )
        done.write_text("fmpy\n", encoding="utf-8")
    return python


def drive(
    python: Path,
    command: str,
    fmu: Path,
    folder: Path,
    inputs: dict[str, Any] | None = None,
    check: bool = True,
    environment: dict[str, str] | None = None,
) -> Any:
    """Run tests/fmu_driver.py under ``python``; its JSON result (or the process)."""
    target = folder / f"{command}-{fmu.stem}-out.json"
    args = [str(python), str(DRIVER), command, str(fmu)]
    if inputs is not None:
        source = folder / f"{command}-{fmu.stem}-in.json"
        source.write_text(json.dumps(inputs), encoding="utf-8")
        args.append(str(source))
    args.append(str(target))
    env = {k: v for k, v in os.environ.items() if k != "PYTHONPATH"}
    env.update(environment or {})
    done = subprocess.run(
        args, cwd=folder, capture_output=True, text=True, timeout=600, env=env, check=False
    )
    if not check:
        return done
    assert done.returncode == 0, done.stderr
    return json.loads(target.read_text(encoding="utf-8"))


def test_the_damper_fmu_runs_in_a_python_without_ecdsim(tmp_path: Path, clean_python: Path) -> None:
    # FMPy in a venv of its own validates the FMU and simulates it, model exchange and
    # co-simulation, without ecdsim (the driver checks that it cannot import it); the
    # results equal ecdsim's heat balance integrated by scipy here.
    from scipy.integrate import solve_ivp

    config_path = variant(tmp_path, "heated", HEATED)
    config = ecdsim.load(config_path)
    fmu = export(config_path, tmp_path / "heated.fmu")
    validated = drive(clean_python, "validate", fmu, tmp_path)
    assert validated == {"problems": [], "ecdsim_importable": False}
    columns = {"time": [0.0, 20.0], "shaft_speed": [0.3, 0.3], "ambient_temperature": [0.0, 0.0]}
    reference = solve_ivp(
        lambda t, y: [reference_rates(config, 0.3, 0.0, y[0], 0.0)[0]],
        (0.0, 20.0),
        [0.0],
        method="DOP853",
        rtol=1e-12,
        atol=1e-12,
        t_eval=np.linspace(0.0, 20.0, 21),
    )
    assert reference.y[0, -1] > 1.0
    for kind, tolerance in (("ModelExchange", 1e-6), ("CoSimulation", 1e-9)):
        got = drive(
            clean_python,
            "simulate",
            fmu,
            tmp_path,
            {
                "kwargs": {
                    "fmi_type": kind,
                    "stop_time": 20.0,
                    "output_interval": 1.0,
                    "input": columns,
                    "relative_tolerance": 1e-10,
                    "output": ["damper_temperature", "damper_torque"],
                }
            },
        )
        assert got["ecdsim_importable"] is False
        # CVode at rtol 1e-10: 1e-6 K; the FMU's RK4 at 1 ms: 1e-9 K.
        assert np.max(np.abs(np.array(got["damper_temperature"]) - reference.y[0])) < tolerance
        last = reference_outputs(config, 0.3, 0.0, got["damper_temperature"][-1])
        assert got["damper_torque"][-1] == pytest.approx(last["damper_torque"], rel=1e-12)
    # Without inputs, a plain simulate_fmu runs the DefaultExperiment (past the slowest
    # deployment of the config).
    plain = drive(clean_python, "simulate", fmu, tmp_path, {"kwargs": {"output_interval": 1.0}})
    assert plain["time"][-1] == pytest.approx(53.0)


# ---- The deployment FMU (pythonfmu) -----------------------------------------------------


def test_deployment_fmu_follows_the_dynamic_method(tmp_path: Path) -> None:
    require("pythonfmu")
    require("fmpy")
    fmu = export(DYNAMIC, tmp_path / "d.fmu", "--deployment")
    out = drive(
        Path(sys.executable),
        "simulate",
        fmu,
        tmp_path,
        {
            "kwargs": {
                "stop_time": 35.0,
                "output_interval": 0.25,
                "output": ["angle", "speed", "latched", "status"],
                "start_values": {"ambient_temperature": 100.0},
            }
        },
    )
    time = np.array(out["time"])
    run = ecdsim.deploy(DYNAMIC, temperatures=100.0, methods="dynamic")
    latch = run.deployment_time("dynamic")[100.0]
    before = time < latch
    trajectory = run.prediction.trajectory("dynamic", time[before])
    # The FMU evaluates the same solution at the same times: equal to rounding.
    assert np.array(out["angle"])[before] == pytest.approx(np.ravel(trajectory.angle), abs=1e-12)
    assert np.array(out["speed"])[before] == pytest.approx(np.ravel(trajectory.speed), abs=1e-12)
    latched = np.array(out["latched"]) > 0.5
    assert not latched[before].any()
    assert latched[~before].all()
    status = np.array(out["status"])
    assert (status[before] == 1).all()  # moving
    assert (status[~before] == 2).all()  # latched
    assert out["angle"][-1] == pytest.approx(1.57, abs=1e-9)  # the travel
    assert out["speed"][-1] == 0.0


def test_deployment_fmu_never_compiles_inside_the_host(tmp_path: Path) -> None:
    # numba inside the host's call into pythonfmu's Python corrupted the host's heap (the
    # process aborted: "corrupted double-linked list", rc 134) when its cache was cold.
    # Run with an empty numba cache (NUMBA_CACHE_DIR) and numba switched on, the FMU must
    # not load numba (the driver's interpreter is the FMU's), compile nothing (the cache
    # stays empty), and follow the dynamic method.
    require("pythonfmu")
    require("fmpy")
    fmu = export(DYNAMIC, tmp_path / "cold.fmu", "--deployment")
    cache = tmp_path / "numba-cache"
    cache.mkdir()
    out = drive(
        Path(sys.executable),
        "simulate",
        fmu,
        tmp_path,
        {
            "kwargs": {
                "stop_time": 20.0,
                "output_interval": 0.5,
                "output": ["angle", "speed", "latched", "status"],
                "start_values": {"ambient_temperature": 100.0},
            }
        },
        environment={"NUMBA_CACHE_DIR": str(cache), "ECDSIM_NUMBA": "1"},
    )
    assert out["numba_loaded"] is False
    assert list(cache.rglob("*.nbi")) == []  # nothing compiled inside the host
    time = np.array(out["time"])
    run = ecdsim.deploy(DYNAMIC, temperatures=100.0, methods="dynamic")
    latch = run.deployment_time("dynamic")[100.0]
    before = time < latch
    assert before.any()
    assert not before.all()
    trajectory = run.prediction.trajectory("dynamic", time[before])
    # The same integration, plain Python in the FMU and compiled here: equal but for
    # rounding (the compiler may contract a*b+c into one fused operation), which the
    # adaptive steps carry on, far below the method's 1e-8 tolerance of the state.
    assert np.array(out["angle"])[before] == pytest.approx(np.ravel(trajectory.angle), abs=1e-9)
    assert np.array(out["speed"])[before] == pytest.approx(np.ravel(trajectory.speed), abs=1e-9)
    assert (np.array(out["status"])[before] == 1).all()  # moving
    assert (np.array(out["status"])[~before] == 2).all()  # latched
    assert out["angle"][-1] == pytest.approx(1.57, abs=1e-9)  # the travel


def test_deployment_fmu_reports_stuck_and_stalled(tmp_path: Path) -> None:
    # A spring that cannot beat the breakaway at release: stuck from t = 0. A spring whose
    # end torque falls below the friction: the run creeps to its static equilibrium and
    # never latches, reported as stalled (not "not latched yet").
    require("pythonfmu")
    stuck = variant(
        tmp_path,
        "stuck",
        ('start_torque = "3.73 N*m"', 'start_torque = "0.9 N*m"'),
        ('end_torque = "1.58 N*m"', 'end_torque = "0.8 N*m"'),
    )
    stalled = variant(tmp_path, "stalled", ('end_torque = "1.58 N*m"', 'end_torque = "0.3 N*m"'))
    for config, expected in ((stuck, 4), (stalled, 5)):
        run = ecdsim.deploy(config, temperatures=25.0, methods="dynamic")
        assert run.prediction.to_dict()["cases"][0]["dynamic"]["status"] in ("stuck", "creep")
        fmu = export(config, tmp_path / f"{config.stem}.fmu", "--deployment")
        out = drive(
            Path(sys.executable),
            "simulate",
            fmu,
            tmp_path,
            {
                "kwargs": {
                    "stop_time": 20.0,
                    "output_interval": 1.0,
                    "output": ["status", "latched", "angle"],
                    "start_values": {"ambient_temperature": 25.0},
                }
            },
        )
        assert set(out["status"]) == {expected}, config.stem
        assert not any(out["latched"])
        assert out["angle"][-1] < 1.57


def test_deployment_fmu_many_instances_in_one_process(tmp_path: Path) -> None:
    # pythonfmu 0.7's loader freed the script module's namespace after an instantiation
    # or two: the second simulate_fmu failed and two live instances crashed the process.
    # Four simulate_fmu calls, then three live instances stepped in turn at different
    # ambient temperatures (each equal to the same instance alone), all in one process.
    require("pythonfmu")
    fmu = export(DYNAMIC, tmp_path / "d.fmu", "--deployment")
    times = [0.0, 5.0, 10.0, 20.0, 40.0]
    runs = [{"start": {"ambient_temperature": t}} for t in (-40.0, 25.0, 100.0)]
    out = drive(
        Path(sys.executable),
        "instances",
        fmu,
        tmp_path,
        {
            "time": times,
            "outputs": ["angle", "speed"],
            "runs": runs,
            "simulations": 4,
        },
    )
    assert len(out["simulations"]) == 4
    assert all(s[-1] == pytest.approx(1.57) for s in out["simulations"])
    assert out["together"] == out["alone"]
    for i, t in enumerate((-40.0, 25.0, 100.0)):
        run = ecdsim.deploy(DYNAMIC, temperatures=t, methods="dynamic")
        angle = np.ravel(run.prediction.trajectory("dynamic", np.array([10.0])).angle)[0]
        assert out["together"][i][2][0] == pytest.approx(angle, abs=1e-12)


def test_deployment_fmu_checks_ecdsim_at_instantiation(tmp_path: Path, clean_python: Path) -> None:
    # Without ecdsim (the clean venv) or with another version (the FMU's stamp altered
    # here), instantiation fails with a message naming the FMU, the version it needs and
    # the Python that loaded it.
    require("pythonfmu")
    from ecdsim import __version__

    fmu = export(DYNAMIC, tmp_path / "d.fmu", "--deployment", "--name", "HingeA")
    inputs = {"kwargs": {"stop_time": 1.0}}
    missing = drive(clean_python, "simulate", fmu, tmp_path, inputs, check=False)
    assert missing.returncode != 0
    assert "Failed to instantiate model" in missing.stderr
    assert (
        f"error: the FMU HingeA runs ecdsim's dynamic method in the Python that loads it "
        f"({clean_python}), which has no ecdsim: install the version that built it, "
        f"pip install 'ecdsim[fmu]=={__version__}'"
    ) in missing.stderr
    other = tmp_path / "other.fmu"
    with zipfile.ZipFile(fmu) as source, zipfile.ZipFile(other, "w") as target:
        for info in source.infolist():
            data = source.read(info)
            if info.filename == "resources/HingeA.py":
                data = data.replace(
                    f'BUILT_WITH = "{__version__}"'.encode(), b'BUILT_WITH = "0.0.1"'
                )
            target.writestr(info, data)
    different = drive(Path(sys.executable), "simulate", other, tmp_path, inputs, check=False)
    assert different.returncode != 0
    assert (
        f"the FMU HingeA was built by ecdsim 0.0.1, and the Python that loads it "
        f"({sys.executable}) has ecdsim {__version__}"
    ) in different.stderr


def test_deployment_fmu_passes_fmpy_validate(tmp_path: Path) -> None:
    require("pythonfmu")
    fmpy = require("fmpy")
    from fmpy.validation import validate_fmu

    fmu = export(DYNAMIC, tmp_path / "d.fmu", "--deployment")
    assert validate_fmu(str(fmu)) == []
    md = fmpy.read_model_description(str(fmu))
    byname = {v.name: v for v in md.modelVariables}
    assert byname["ambient_temperature"].unit == "degC"
    assert byname["angle"].unit == "rad"
    assert byname["speed"].unit == "rad/s"
    assert byname["status"].type == "Enumeration"
    items = {i.name for i in md.typeDefinitions[0].items}
    assert {"moving", "latched", "stuck", "stalled"} <= items
    slowest = max(ecdsim.deploy(DYNAMIC, methods="dynamic").deployment_time("dynamic").values())
    assert slowest < float(md.defaultExperiment.stopTime) < 1.25 * slowest
    assert md.coSimulation.modelIdentifier.startswith("d_")


# ---- The command line -------------------------------------------------------------------


def test_export_fmu_errors_are_one_line_exit_2(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    runner = CliRunner()
    result = runner.invoke(app, ["export-fmu", str(PAPER), "--deployment", "-o", "x.fmu"])
    assert result.exit_code == 2
    assert result.stderr.count("\n") == 1
    assert "load.inertia: missing" in result.stderr
    result = runner.invoke(app, ["export-fmu", str(PAPER), "-o", str(tmp_path / "x.zip")])
    assert result.exit_code == 2
    assert "--out" in result.stderr
    for bad, why in (
        ("1abc", "expected a letter"),
        ("json", "a Python module of that name"),
        ("class", "expected a letter"),
    ):
        result = runner.invoke(
            app, ["export-fmu", str(PAPER), "-o", str(tmp_path / "x.fmu"), "--name", bad]
        )
        assert result.exit_code == 2, bad
        assert result.stderr.count("\n") == 1
        assert f"--name '{bad}': {why}" in result.stderr
    monkeypatch.setitem(sys.modules, "pythonfmu.builder", None)
    result = runner.invoke(
        app, ["export-fmu", str(DYNAMIC), "--deployment", "-o", str(tmp_path / "x.fmu")]
    )
    assert result.exit_code == 2
    assert pip_install("fmu") in result.stderr  # this installation's command (issue 23)
    monkeypatch.setenv("CC", str(tmp_path / "no-such-compiler"))
    result = runner.invoke(app, ["export-fmu", str(PAPER), "-o", str(tmp_path / "x.fmu")])
    assert result.exit_code == 2
    assert result.stderr.count("\n") == 1
    assert "cannot run the C compiler" in result.stderr
    assert not (tmp_path / "x.fmu").exists()


def test_the_model_identifier_is_unique_per_export(tmp_path: Path) -> None:
    fmpy = require("fmpy")
    heated = variant(tmp_path, "heated", HEATED)
    a = export(DYNAMIC, tmp_path / "a.fmu")
    b = export(heated, tmp_path / "a2.fmu")
    c = export(heated, tmp_path / "b.fmu", "--name", "MyDamper")

    def ident(path: Path) -> str:
        return str(fmpy.read_model_description(str(path)).coSimulation.modelIdentifier)

    assert ident(a).startswith("a_")
    assert ident(b).startswith("a2_")
    assert ident(c) == "MyDamper"
    assert len({ident(a), ident(b), ident(c)}) == 3
    with zipfile.ZipFile(c) as archive:
        assert "binaries/linux64/MyDamper.so" in archive.namelist()
        assert {"sources/fmu2.c", "sources/fmi2.h", "sources/model.h"} <= set(archive.namelist())


def test_a_compliant_mesh_is_refused_by_the_damper_fmu(tmp_path: Path) -> None:
    # The damper FMU is rigid from shaft to rotor: a compliant mesh would be dropped.
    path = variant(
        tmp_path,
        "compliant",
        ('lost_motion = "0 deg"', 'lost_motion = "0.25 deg"\nstiffness = "2 kN*m/rad"'),
    )
    result = CliRunner().invoke(app, ["export-fmu", str(path), "-o", str(tmp_path / "x.fmu")])
    assert result.exit_code == 2
    assert result.stderr.count("\n") == 1
    assert "gearbox.stiffness: a compliant mesh is not in the damper FMU" in result.stderr
    assert not (tmp_path / "x.fmu").exists()


def test_help_lists_the_options_and_its_example_runs(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    from tests.helptext import assert_options, read_help, run_example

    runner = CliRunner()
    screen = read_help(runner, app, ["export-fmu"])
    assert_options(screen, {"--out": "-o", "--deployment": None, "--name": None, "--help": None})
    run_example(runner, app, screen, tmp_path, monkeypatch)
    assert (tmp_path / "damper.fmu").read_bytes().startswith(b"PK")  # a zip archive


# ---- make test's set-up: a C compiler ----------------------------------------------------


def _ensure_cc(tmp_path: Path, fakes: dict[str, str]) -> subprocess.CompletedProcess[str]:
    """scripts/ensure-cc.sh with a PATH of bash and ``fakes`` only (name -> script body)."""
    bin_dir = tmp_path / "bin"
    bin_dir.mkdir(parents=True)
    bash = shutil.which("bash")
    assert bash is not None
    (bin_dir / "bash").symlink_to(bash)
    for name, body in fakes.items():
        (bin_dir / name).write_text(f"#!{bash}\n{body}")
        (bin_dir / name).chmod(0o755)
    env = {k: v for k, v in os.environ.items() if k != "CC"}
    return subprocess.run(
        [bash, str(ROOT / "scripts" / "ensure-cc.sh")],
        env={**env, "PATH": str(bin_dir)},
        capture_output=True,
        text=True,
        check=False,
    )


def test_make_test_finds_or_installs_a_c_compiler(tmp_path: Path) -> None:
    # A compiler on the PATH is left alone; without one and without apt-get, one line
    # naming the package and exit 2 (never a failure halfway through the suite).
    assert _ensure_cc(tmp_path / "a", {"cc": "exit 0"}).returncode == 0
    missing = _ensure_cc(tmp_path / "b", {})
    assert missing.returncode == 2
    lines = missing.stderr.strip().splitlines()
    assert len(lines) == 1, missing.stderr
    assert "'gcc'" in lines[0]
    assert "apt-get is not available" in lines[0]
    assert "ensure-cc.sh" in (ROOT / "Makefile").read_text(encoding="utf-8")
