"""The damper FMU in C: FMI 2.0 model exchange and co-simulation, no Python at run time.

:func:`build_damper_fmu` writes an FMU whose shared library is compiled at export by
the system's C compiler from three sources, which the FMU also carries (``sources/``):

* ``fmi2.h``, the FMI 2.0 interface, and ``fmu2.c``, the FMI boundary (instances,
  the FMI rules, the co-simulation RK4), shipped with ecdsim (``ecdsim/fmu/c``);
* ``model.h``, written here: the variables of this config, the physics translated from
  :mod:`ecdsim.fmu.equations` by :mod:`ecdsim.fmu.ctranslate`, and the glue that binds
  each argument of those functions to an FMU variable of the same name.

The physics is therefore ecdsim's own Python source, not a copy: change a law in
:mod:`ecdsim.physics` (the laws the dynamic kernel compiles) and the next export carries it.
"""

from __future__ import annotations

import inspect
import math
import os
import platform
import shlex
import shutil
import subprocess
import tempfile
import xml.etree.ElementTree as ET
import zipfile
from dataclasses import dataclass
from importlib import resources
from pathlib import Path

from ecdsim.fmu import FmuCompilerError, ctranslate, equations
from ecdsim.fmu.model import DAMPER_OUTPUTS, DamperModel

# The longest internal Runge-Kutta step of co-simulation [s] (the parameter max_step).
MAX_STEP = 1e-3
# The nominal value of a temperature state [degC], for the importer's error control.
STATE_NOMINAL = 100.0

# FMI 2.0 units: name -> exponents of the SI base units (and an offset for degC).
UNITS: dict[str, dict[str, float]] = {
    "rad/s": {"rad": 1, "s": -1},
    "rad": {"rad": 1},
    "N.m": {"kg": 1, "m": 2, "s": -2},
    "N.m.s/rad": {"kg": 1, "m": 2, "s": -1, "rad": -1},
    "N.m/K": {"kg": 1, "m": 2, "s": -2, "K": -1},
    "kg.m2": {"kg": 1, "m": 2},
    "degC": {"K": 1, "offset": 273.15},
    "1/K": {"K": -1},
    "K/s": {"K": 1, "s": -1},
    "J/K": {"kg": 1, "m": 2, "s": -2, "K": -1},
    "K/W": {"kg": -1, "m": -2, "s": 3, "K": 1},
    "W": {"kg": 1, "m": 2, "s": -3},
    "s": {"s": 1},
}
_INF = math.inf

# Each model value a host may set: (unit, lower bound, bound open, upper bound, meaning).
PARAMETERS: dict[str, tuple[str, float, bool, float, str]] = {
    "gear_ratio": ("", 0.0, True, _INF, "gear ratio N, damper turns per slow-shaft turn"),
    "damping_rate": ("N.m.s/rad", 0.0, False, _INF, "BD, the damper's rate at T_ref"),
    "reference_temperature": ("degC", -273.15, True, _INF, "T_ref, where BD is rated"),
    "damping_temperature_coefficient": ("1/K", -_INF, False, _INF, "c of Eq. 1"),
    "peak_speed": ("rad/s", 0.0, True, _INF, "omega_peak at T_ref (Kloss roll-off)"),
    "resistivity_coefficient": ("1/K", -_INF, False, _INF, "alpha of the Kloss peak speed"),
    "gearbox_damping_rate": ("N.m.s/rad", 0.0, False, _INF, "BG at the damper shaft"),
    "gearbox_damping_fraction": ("", 0.0, False, _INF, "BG as a fraction of BD"),
    "forward_efficiency": ("", 0.0, True, 1.0, "eta_f of the lossy mesh, driven forward"),
    "damper_coulomb_friction": ("N.m", 0.0, False, _INF, "FD at the damper shaft"),
    "gearbox_coulomb_friction": ("N.m", 0.0, False, _INF, "FG at the damper shaft"),
    "lubrication_friction_slope": ("N.m/K", -_INF, False, _INF, "FL_T = slope T + at_0C"),
    "lubrication_friction_at_0c": ("N.m", -_INF, False, _INF, "FL_T at 0 degC"),
    "lubrication_temperatures": ("degC", -273.15, True, _INF, "FL_T table temperature"),
    "lubrication_frictions": ("N.m", -_INF, False, _INF, "FL_T table value"),
    "static_friction_factor": ("", 1.0, False, _INF, "f_D, breakaway over kinetic"),
    "stribeck_speed": ("rad/s", 0.0, True, _INF, "w_St of the Stribeck curve (slow shaft)"),
    "heat_capacity": ("J/K", 0.0, True, _INF, "C of the damper (the rotor with a housing)"),
    "thermal_resistance": ("K/W", 0.0, True, _INF, "R to ambient (to the housing)"),
    "housing_heat_capacity": ("J/K", 0.0, True, _INF, "C_h of the housing"),
    "housing_thermal_resistance": ("K/W", 0.0, True, _INF, "R_h, housing to ambient"),
}
OUTPUT_INFO: dict[str, tuple[str, str]] = {
    "damper_torque": ("N.m", "damping torque at the slow shaft, opposing the speed"),
    "friction_torque": ("N.m", "ECD sliding friction at the slow shaft, opposing (0 at rest)"),
    "coulomb_friction": ("N.m", "FECD, the ECD's Coulomb friction at the ambient (Eq. 2, 4)"),
    "breakaway_friction": ("N.m", "f_D FECD, what the ECD holds at rest"),
    "eddy_power": ("W", "eddy-current power dissipated in the damper"),
}


@dataclass(frozen=True)
class Variable:
    """One FMI ScalarVariable of the damper FMU (a Real unless ``boolean``)."""

    name: str
    causality: str  # parameter, input, output or local
    unit: str
    description: str
    start: float | None = None
    minimum: float = -_INF
    open_minimum: bool = False
    maximum: float = _INF
    derivative_of: str | None = None
    boolean: bool = False


@dataclass(frozen=True)
class Layout:
    """The damper FMU's variables in value-reference order, and its structure."""

    reals: tuple[Variable, ...]
    booleans: tuple[Variable, ...]
    states: tuple[str, ...]
    parameter_arrays: dict[str, int]  # array argument -> value reference of its first entry

    def vr(self, name: str) -> int:
        """The value reference of a Real variable."""
        for i, variable in enumerate(self.reals):
            if variable.name == name:
                return i
        raise KeyError(name)


def layout(model: DamperModel) -> Layout:
    """The damper FMU's variables for ``model``: inputs, outputs, states, parameters."""
    reals = [
        Variable("shaft_speed", "input", "rad/s", "slow-shaft speed u", start=0.0),
        Variable(
            "ambient_temperature",
            "input",
            "degC",
            "ambient temperature (friction, heat sink)",
            start=model.ambient,
            minimum=-273.15,
            open_minimum=True,
        ),
    ]
    reals += [Variable(name, "output", *OUTPUT_INFO[name]) for name in DAMPER_OUTPUTS]
    states: tuple[str, ...] = ()
    if model.heating:
        states = (
            ("damper_temperature", "housing_temperature")
            if model.housing
            else ("damper_temperature",)
        )
        meanings = {
            "damper_temperature": "damper (rotor) temperature T_d, a continuous state",
            "housing_temperature": "housing temperature T_h, a continuous state",
        }
        reals += [Variable(name, "output", "degC", meanings[name]) for name in states]
        reals += [
            Variable(
                f"der({name})", "local", "K/s", f"time derivative of {name}", derivative_of=name
            )
            for name in states
        ]
    arrays: dict[str, int] = {}
    for name in model.parameters:
        unit, low, open_low, high, meaning = PARAMETERS[name]
        value = model.values[name]
        if isinstance(value, tuple):
            arrays[name] = len(reals)
            reals += [
                Variable(
                    f"{name}[{i + 1}]",
                    "parameter",
                    unit,
                    f"{meaning} {i + 1}",
                    start=float(entry),
                    minimum=low,
                    open_minimum=open_low,
                    maximum=high,
                )
                for i, entry in enumerate(value)
            ]
        else:
            reals.append(
                Variable(
                    name,
                    "parameter",
                    unit,
                    meaning,
                    start=float(value),
                    minimum=low,
                    open_minimum=open_low,
                    maximum=high,
                )
            )
    reals.append(
        Variable(
            "max_step",
            "parameter",
            "s",
            "co-simulation: longest internal RK4 step",
            start=MAX_STEP,
            minimum=0.0,
            open_minimum=True,
        )
    )
    booleans = (
        Variable(
            "input_extrapolation",
            "parameter",
            "",
            "co-simulation: extrapolate the inputs over a step from the last two "
            "communication points (unless input derivatives are set)",
            start=1.0,
            boolean=True,
        ),
    )
    return Layout(tuple(reals), booleans, states, arrays)


# ---- model.h --------------------------------------------------------------------------


def _c_string(text: str) -> str:
    return '"' + text.replace("\\", "\\\\").replace('"', '\\"') + '"'


def _array(kind: str, name: str, items: list[str]) -> str:
    return f"static const {kind} {name}[] = {{{', '.join(items) or '0'}}};"


def _bindings(model: DamperModel, shape: Layout) -> dict[str, str]:
    """The C expression each argument of the equations takes in the glue."""
    ambient = f"r[{shape.vr('ambient_temperature')}]"
    bound = {
        "shaft_speed": f"r[{shape.vr('shaft_speed')}]",
        "ambient_temperature": ambient,
        "damper_temperature": ambient,
        "housing_temperature": ambient,
    }
    for state in shape.states:
        bound[state] = f"r[{shape.vr(state)}]"
    for name, value in model.values.items():
        if name in shape.parameter_arrays:
            bound[name] = f"&r[{shape.parameter_arrays[name]}]"
        elif name in model.parameters:
            bound[name] = f"r[{shape.vr(name)}]"
        elif isinstance(value, bool):
            bound[name] = "1" if value else "0"
        elif isinstance(value, int):
            bound[name] = str(value)
        elif isinstance(value, tuple):
            bound[name] = "ECD_NO_TABLE"
        else:
            bound[name] = ctranslate.c_literal(value)
    return bound


def _call(function_name: str, arguments: list[str], bound: dict[str, str], outs: list[str]) -> str:
    texts = [bound[name] for name in arguments] + outs
    return f"    ecd_{function_name}({', '.join(texts)});"


def model_header(model: DamperModel, shape: Layout, guid: str) -> str:
    """``model.h``: the variables, the translated physics and the glue."""
    reals, n = shape.reals, len(shape.reals)
    causality = {
        "parameter": "ECD_PARAMETER",
        "input": "ECD_INPUT",
        "output": "ECD_OUTPUT",
        "local": "ECD_LOCAL",
    }
    inputs = [shape.vr(name) for name in ("shaft_speed", "ambient_temperature")]
    lines = [
        "/* The damper FMU's model, written by ecdsim at export (ecdsim.fmu.native). */",
        f"#define MODEL_GUID {_c_string(guid)}",
        f"#define N_REAL {n}",
        f"#define N_BOOLEAN {len(shape.booleans)}",
        f"#define N_STATES {len(shape.states)}",
        f"#define N_INPUTS {len(inputs)}",
        f"#define VR_MAX_STEP {shape.vr('max_step')}",
        "#define VB_INPUT_EXTRAPOLATION 0",
        f"#define STATE_NOMINAL {ctranslate.c_literal(STATE_NOMINAL)}",
        _array("char *const", "REAL_NAME", [_c_string(v.name) for v in reals]),
        _array("char *const", "REAL_UNIT", [_c_string(v.unit or "1") for v in reals]),
        _array("double", "REAL_START", [ctranslate.c_literal(v.start or 0.0) for v in reals]),
        _array("unsigned char", "REAL_CAUSALITY", [causality[v.causality] for v in reals]),
        _array("double", "REAL_MIN", [ctranslate.c_literal(v.minimum) for v in reals]),
        _array("double", "REAL_MAX", [ctranslate.c_literal(v.maximum) for v in reals]),
        _array("unsigned char", "REAL_MIN_OPEN", ["1" if v.open_minimum else "0" for v in reals]),
        _array("fmi2Boolean", "BOOLEAN_START", ["1" if v.start else "0" for v in shape.booleans]),
        _array("fmi2ValueReference", "INPUT_VR", [str(vr) for vr in inputs]),
        _array("fmi2ValueReference", "STATE_VR", [str(shape.vr(s)) for s in shape.states]),
        _array(
            "fmi2ValueReference",
            "DERIVATIVE_VR",
            [str(shape.vr(f"der({s})")) for s in shape.states],
        ),
        "static const double ECD_NO_TABLE[] = {0.0};",
        "",
        "/* ---- The physics, translated from ecdsim's Python source ---- */",
        ctranslate.translate(
            [equations.damper_outputs] + ([equations.damper_heating] if shape.states else [])
        ),
        "/* ---- Glue: the equations' arguments bound to the variables of the same name ---- */",
    ]
    bound = _bindings(model, shape)
    start = [f"    r[{shape.vr(s)}] = r[{shape.vr('ambient_temperature')}];" for s in shape.states]
    lines += ["static void model_start_states(double *r) {", *start, "    (void)r;", "}"]
    outs = [f"&r[{shape.vr(name)}]" for name in DAMPER_OUTPUTS]
    arguments = list(inspect.signature(equations.damper_outputs).parameters)
    lines += [
        "static void model_outputs(double *r) {",
        _call("damper_outputs", arguments, bound, outs),
        "}",
    ]
    lines.append("static void model_derivatives(double *r) {")
    if shape.states:
        derivatives = [f"&r[{shape.vr(f'der({s})')}]" for s in shape.states]
        if len(derivatives) == 1:
            lines.append("    double unused;")
            derivatives.append("&unused")
        arguments = list(inspect.signature(equations.damper_heating).parameters)
        lines.append(_call("damper_heating", arguments, bound, derivatives))
    else:
        lines.append("    (void)r; /* no [damper.thermal]: no states */")
    lines.append("}")
    return "\n".join(lines) + "\n"


# ---- modelDescription.xml -------------------------------------------------------------


def _number(value: float) -> str:
    return repr(float(value))


def _units_element(used: set[str]) -> ET.Element:
    element = ET.Element("UnitDefinitions")
    for name in sorted(used):
        unit = ET.SubElement(element, "Unit", name=name)
        ET.SubElement(
            unit,
            "BaseUnit",
            {k: _number(v) if k == "offset" else str(int(v)) for k, v in UNITS[name].items()},
        )
    return element


def model_description(
    model: DamperModel,
    shape: Layout,
    identifier: str,
    guid: str,
    version: str,
    stop_time: float,
    description: str,
) -> bytes:
    """The damper FMU's ``modelDescription.xml`` (FMI 2.0, ME and CS)."""
    root = ET.Element(
        "fmiModelDescription",
        {
            "fmiVersion": "2.0",
            "modelName": identifier,
            "guid": guid,
            "description": description,
            "author": "ecdsim",
            "version": version,
            "generationTool": f"ecdsim {version}",
            "variableNamingConvention": "structured",
            "numberOfEventIndicators": "0",
        },
    )
    common = {
        "modelIdentifier": identifier,
        "canGetAndSetFMUstate": "true",
        "canSerializeFMUstate": "true",
        "providesDirectionalDerivative": "false",
    }
    exchange = ET.SubElement(
        root, "ModelExchange", {**common, "completedIntegratorStepNotNeeded": "true"}
    )
    cosim = ET.SubElement(
        root,
        "CoSimulation",
        {
            **common,
            "canHandleVariableCommunicationStepSize": "true",
            "canInterpolateInputs": "true",
            "maxOutputDerivativeOrder": "0",
        },
    )
    for kind in (exchange, cosim):
        files = ET.SubElement(kind, "SourceFiles")
        ET.SubElement(files, "File", name="fmu2.c")
    root.append(_units_element({v.unit for v in shape.reals if v.unit}))
    categories = ET.SubElement(root, "LogCategories")
    ET.SubElement(
        categories,
        "Category",
        name="logStatusError",
        description="errors: a refused call, a value out of range",
    )
    ET.SubElement(
        root,
        "DefaultExperiment",
        startTime="0.0",
        stopTime=_number(stop_time),
        stepSize=_number(MAX_STEP),
        tolerance="1e-06",
    )
    variables = ET.SubElement(root, "ModelVariables")
    index = {v.name: i + 1 for i, v in enumerate(shape.reals)}
    for vr, variable in enumerate(shape.reals):
        attributes = {
            "name": variable.name,
            "valueReference": str(vr),
            "description": variable.description,
            "causality": variable.causality,
            "variability": "fixed" if variable.causality == "parameter" else "continuous",
        }
        if variable.causality == "parameter":
            attributes["initial"] = "exact"
        elif variable.causality in ("output", "local"):
            attributes["initial"] = "calculated"
        scalar = ET.SubElement(variables, "ScalarVariable", attributes)
        real: dict[str, str] = {}
        if variable.derivative_of is not None:
            real["derivative"] = str(index[variable.derivative_of])
        if variable.unit:
            real["unit"] = variable.unit
        if variable.name in shape.states:
            real["nominal"] = _number(STATE_NOMINAL)
        if math.isfinite(variable.minimum):
            real["min"] = _number(variable.minimum)
        if math.isfinite(variable.maximum):
            real["max"] = _number(variable.maximum)
        if variable.start is not None:
            real["start"] = _number(variable.start)
        ET.SubElement(scalar, "Real", real)
    for vr, variable in enumerate(shape.booleans):
        scalar = ET.SubElement(
            variables,
            "ScalarVariable",
            name=variable.name,
            valueReference=str(vr),
            description=variable.description,
            causality="parameter",
            variability="fixed",
            initial="exact",
        )
        ET.SubElement(scalar, "Boolean", start="true" if variable.start else "false")
    structure = ET.SubElement(root, "ModelStructure")
    temperature = "damper_temperature" if shape.states else "ambient_temperature"
    depends = {
        "damper_torque": ["shaft_speed", temperature],
        "friction_torque": ["shaft_speed", "ambient_temperature"],
        "coulomb_friction": ["ambient_temperature"],
        "breakaway_friction": ["ambient_temperature"],
        "eddy_power": ["shaft_speed", temperature],
        "damper_temperature": ["damper_temperature"],
        "housing_temperature": ["housing_temperature"],
        "der(damper_temperature)": ["shaft_speed", "damper_temperature"]
        + (["housing_temperature"] if model.housing else ["ambient_temperature"]),
        "der(housing_temperature)": [
            "ambient_temperature",
            "damper_temperature",
            "housing_temperature",
        ],
    }

    def unknown(parent: ET.Element, name: str, dependencies: bool) -> None:
        attributes = {"index": str(index[name])}
        if dependencies:
            attributes["dependencies"] = " ".join(
                str(i) for i in sorted(index[d] for d in depends[name])
            )
        ET.SubElement(parent, "Unknown", attributes)

    outputs = ET.SubElement(structure, "Outputs")
    for variable in shape.reals:
        if variable.causality == "output":
            unknown(outputs, variable.name, True)
    if shape.states:
        derivatives = ET.SubElement(structure, "Derivatives")
        for state in shape.states:
            unknown(derivatives, f"der({state})", True)
    initial = ET.SubElement(structure, "InitialUnknowns")
    for variable in shape.reals:
        if variable.causality in ("output", "local"):
            unknown(initial, variable.name, False)  # no list: depends on every known
    ET.indent(root, space="  ")
    return bytes(ET.tostring(root, encoding="UTF-8", xml_declaration=True)) + b"\n"


# ---- Compiling and packing ------------------------------------------------------------


def platform_folder() -> tuple[str, str]:
    """The FMI 2.0 platform folder and shared-library suffix of this machine."""
    system = platform.system()
    bits = "64" if platform.architecture()[0] == "64bit" else "32"
    if system == "Linux":
        return f"linux{bits}", ".so"
    if system == "Darwin":
        return f"darwin{bits}", ".dylib"
    if system == "Windows":
        return f"win{bits}", ".dll"
    raise FmuCompilerError(f"no FMI 2.0 platform name for {system}: build on Linux or macOS")


def compiler() -> list[str]:
    """The C compiler command: $CC, else cc, gcc or clang on the PATH."""
    given = os.environ.get("CC", "").strip()
    if given:
        return shlex.split(given)
    for name in ("cc", "gcc", "clang"):
        found = shutil.which(name)
        if found:
            return [found]
    raise FmuCompilerError(
        "the damper FMU is compiled at export with the system's C compiler, and none was "
        "found (cc, gcc, clang, or $CC): install one (Debian: apt-get install gcc)"
    )


def template(name: str) -> str:
    """A C source shipped with ecdsim (ecdsim/fmu/c)."""
    return resources.files("ecdsim.fmu").joinpath("c", name).read_text(encoding="utf-8")


def compile_library(sources: Path, library: Path) -> None:
    """Compile ``sources/fmu2.c`` (with its headers) into the shared ``library``.

    ``-ffp-contract=off``: no fused multiply-adds, so the translated physics rounds as
    CPython does (ecdsim.fmu.ctranslate).
    """
    command = [
        *compiler(),
        "-shared",
        "-fPIC",
        "-O2",
        "-std=c99",
        "-ffp-contract=off",
        "-fvisibility=hidden",
        "-Wall",
        "-o",
        str(library),
        str(sources / "fmu2.c"),
        "-lm",
    ]
    try:
        done = subprocess.run(command, capture_output=True, text=True, timeout=300, check=False)
    except OSError as exc:
        raise FmuCompilerError(f"cannot run the C compiler {command[0]}: {exc}") from None
    if done.returncode != 0 or not library.is_file():
        detail = (done.stderr or done.stdout).strip().splitlines()
        first = detail[0] if detail else f"exit status {done.returncode}"
        raise FmuCompilerError(f"the C compiler {command[0]} failed on the damper FMU: {first}")


def build_damper_fmu(
    model: DamperModel,
    identifier: str,
    guid: str,
    version: str,
    stop_time: float,
    config_text: bytes,
    description: str,
) -> bytes:
    """The damper FMU of ``model`` as the bytes of its zip archive."""
    shape = layout(model)
    folder, suffix = platform_folder()
    with tempfile.TemporaryDirectory(prefix="ecdsim-fmu-") as work:
        sources = Path(work) / "sources"
        sources.mkdir()
        files = {
            "fmi2.h": template("fmi2.h"),
            "fmu2.c": template("fmu2.c"),
            "model.h": model_header(model, shape, guid),
        }
        for name, text in files.items():
            (sources / name).write_text(text, encoding="utf-8")
        library = Path(work) / f"{identifier}{suffix}"
        compile_library(sources, library)
        xml = model_description(model, shape, identifier, guid, version, stop_time, description)
        archive = Path(work) / "out.fmu"
        with zipfile.ZipFile(archive, "w", zipfile.ZIP_DEFLATED) as fmu:
            fmu.writestr("modelDescription.xml", xml)
            fmu.write(library, f"binaries/{folder}/{identifier}{suffix}")
            for name, text in files.items():
                fmu.writestr(f"sources/{name}", text)
            fmu.writestr("resources/ecdsim_config.toml", config_text)
        return archive.read_bytes()
