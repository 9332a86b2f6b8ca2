"""FMU export (FMI 2.0) of the damper, or of the whole deployment (docs/fmu.md).

:func:`build_fmu` writes one of two FMUs of a config:

* **the damper** (default): the ECD referred to the slow shaft (inputs shaft speed and
  ambient temperature; outputs damper torque, frictions, eddy-current power and, with
  ``[damper.thermal]``, the damper's temperature as a continuous state), for model
  exchange and co-simulation, in C compiled at export by the system's C compiler from
  ecdsim's own physics functions (:mod:`ecdsim.fmu.native`): it needs no Python;
* **the deployment** (``deployment=True``): the spring-driven hinge by the dynamic
  method (no inputs; outputs angle, speed, latch flag, status), for co-simulation,
  built with pythonfmu (``pip install 'ecdsim[fmu]'``), whose loader runs the model in
  the host's Python: it needs ecdsim, of the version that built it, where it runs.

Each export has its own model identifier (``name``, or one derived from the file name
and the config), so that several FMUs load side by side.

A config whose ``[load]`` is a marked placeholder (``ecdsim fit drop-test -o`` without
``--config``) is exported, with a
:class:`~ecdsim.config.placeholder.PlaceholderLoadWarning` and the FMU's description
saying so (the deployment FMU's whole motion, the damper FMU's default stop time are the
stand-in load's).
"""

from __future__ import annotations

import hashlib
import importlib.util
import keyword
import math
import re
import shutil
import sys
import tempfile
import uuid
import xml.etree.ElementTree as ET
import zipfile
from pathlib import Path
from typing import TYPE_CHECKING, Any

from ecdsim.config import ConfigError

if TYPE_CHECKING:
    from ecdsim.config import Config

__all__ = [
    "FmuCompilerError",
    "FmuDependencyError",
    "FmuNameError",
    "build_fmu",
    "model_identifier",
]

# The deployment FMU's script (resources/<name>.py), run by pythonfmu's loader.
#
# pythonfmu 0.7's loader (libpythonfmu-export, findClass) runs the script in its module's
# namespace at every instantiation, then releases a reference to that namespace it never
# took (a Py_DECREF of the borrowed PyModule_GetDict). After an instantiation or two the
# module's dictionary is freed while the module still uses it: the next instantiation in
# the process fails ("module ... has no attribute ...") or the process crashes. The
# script therefore holds one more reference each time it runs, in a list kept on the
# pythonfmu package (loaded for the life of the process): the loader's extra release is
# balanced, at the cost of a few bytes per instantiation.
#
# The version check: a missing or different ecdsim is reported on the host's standard
# error and as the instantiation's error (pythonfmu passes the latter to the FMI logger
# only with debug logging on), and the instantiation fails.
_SCRIPT = '''"""{doc} ({name}, an FMU built by ecdsim {version}; docs/fmu.md)."""

import sys

import pythonfmu

pythonfmu.__dict__.setdefault("_ecdsim_namespaces", []).append(globals())

BUILT_WITH = "{version}"
try:
    import ecdsim
except ImportError:
    PROBLEM = (
        "the FMU {name} runs ecdsim's dynamic method in the Python that loads it "
        f"({{sys.executable}}), which has no ecdsim: install the version that built it, "
        "pip install 'ecdsim[fmu]=={version}'"
    )
else:
    PROBLEM = None
    if ecdsim.__version__ != BUILT_WITH:
        PROBLEM = (
            f"the FMU {name} was built by ecdsim {{BUILT_WITH}}, and the Python that loads "
            f"it ({{sys.executable}}) has ecdsim {{ecdsim.__version__}}: install "
            f"ecdsim=={{BUILT_WITH}}, or export the FMU again with this ecdsim"
        )

if PROBLEM is None:
    from ecdsim.fmu.slaves import DeploymentSlave as Base
else:
    from pythonfmu import Fmi2Slave as Base


class {name}(Base):
    """{doc}"""

    if PROBLEM is not None:

        def __init__(self, **kwargs):
            print("error: " + PROBLEM, file=sys.stderr, flush=True)
            raise ImportError(PROBLEM)

        def do_step(self, current_time, step_size):
            return False
'''
# Units of the deployment FMU's variables (FMI unit names; see native.UNITS).
_DEPLOYMENT_UNITS = {
    "ambient_temperature": "degC",
    "damping_rate": "N.m.s/rad",
    "damping_temperature_coefficient": "1/K",
    "damper_coulomb_friction": "N.m",
    "gearbox_coulomb_friction": "N.m",
    "load_inertia": "kg.m2",
    "start_torque": "N.m",
    "end_torque": "N.m",
    "angle": "rad",
    "speed": "rad/s",
}
_STATUS_TYPE = "ecdsim.DeploymentStatus"
# The damper FMU's description for a placeholder config: only its stop time is the load's.
PLACEHOLDER_STOP_TIME = (
    "the config's [load] is a marked placeholder, so the default experiment's stop time is "
    "a stand-in load's"
)


class FmuDependencyError(ImportError):
    """pythonfmu is not installed; the message says how to install it."""


class FmuNameError(ValueError):
    """A model identifier (``--name``) that cannot name an FMU; the message says why."""


class FmuCompilerError(RuntimeError):
    """No C compiler for the damper FMU, or it failed; the message says which and how."""


def model_identifier(name: str | None, out: Path, kind: str, config_text: bytes) -> str:
    """The FMU's model identifier: ``name`` checked, or ``<file stem>_<8 hex digits>``.

    The digits hash the kind of FMU, ecdsim's version, the config and the stem, so that
    two exports of different configs (or to different files) never share an identifier.
    A given name must be a Python identifier (the deployment FMU's module and class bear
    it, as does the shared library) that names no module the host could already import.
    """
    from ecdsim import __version__

    if name is not None:
        if not re.fullmatch(r"[A-Za-z][A-Za-z0-9_]{0,63}", name) or keyword.iskeyword(name):
            raise FmuNameError(
                f"--name {name!r}: expected a letter then up to 63 letters, digits or "
                "underscores (it names the FMU's library and, for the deployment FMU, its "
                "Python module)"
            )
        if name in sys.stdlib_module_names or importlib.util.find_spec(name) is not None:
            raise FmuNameError(
                f"--name {name!r}: a Python module of that name exists, which the "
                "deployment FMU's loader would import instead of the FMU's own; choose another"
            )
        return name
    stem = re.sub(r"[^A-Za-z0-9_]", "_", out.stem)[:40] or "fmu"
    if not stem[0].isalpha():
        stem = "fmu_" + stem
    digest = hashlib.sha256(
        b"\0".join([kind.encode(), __version__.encode(), stem.encode(), config_text])
    ).hexdigest()[:8]
    return f"{stem}_{digest}"


def _guid(identifier: str, config_text: bytes) -> str:
    from ecdsim import __version__

    digest = hashlib.sha256(config_text).hexdigest()
    return (
        "{"
        + str(uuid.uuid5(uuid.NAMESPACE_URL, f"ecdsim:{__version__}:{identifier}:{digest}"))
        + "}"
    )


def _round_up(value: float) -> float:
    """``value`` rounded up to two significant digits (a tidy stop time)."""
    scale = 10.0 ** (math.floor(math.log10(value)) - 1)
    return math.ceil(value / scale - 1e-9) * scale


def _stop_time(config: Config, deployment: bool) -> float:
    """The DefaultExperiment's stop time: 10 % past the slowest deployment [s].

    Over the config's analysis temperatures, by the dynamic method for the deployment
    FMU (its latch, settling or sticking time) and by the exact quasi-static solution for
    the damper FMU (which needs no inertia); 100 s where no case ends at a finite time.
    """
    import numpy as np

    from ecdsim.deployment import ModelDomainError, predict

    methods = ["dynamic"] if deployment else ["exact"]
    try:
        prediction = predict(
            config.system, config.temperatures, methods, dynamics=config.spec.dynamics()
        )
    except ModelDomainError as exc:  # the config's own temperatures: a one-line error
        raise ConfigError([str(exc)], config.source) from None
    if deployment:
        solution: Any = prediction.solutions["dynamic"]
        result = solution.result
        ends = np.concatenate(
            [
                np.ravel(result.deployment_time),
                np.ravel(result.final_time),
                np.ravel(np.where(result.stuck, result.stuck_time, np.nan)),
            ]
        )
    else:
        ends = np.ravel(prediction.solutions["exact"].deployment_time)
    finite = ends[np.isfinite(ends) & (ends > 0.0)]
    return _round_up(1.1 * float(finite.max())) if finite.size else 100.0


def _check(config: Config, deployment: bool) -> None:
    if deployment and config.spec.dynamics() is None:
        raise ConfigError(
            [
                "load.inertia: missing; the deployment FMU runs the dynamic method, which "
                "needs the load's moment of inertia, e.g. inertia = '5 kg*m^2' in [load]"
            ],
            config.source,
        )
    if not deployment and config.spec.gearbox.stiffness is not None:
        # The damper FMU's ECD is rigid from the slow shaft to the rotor: a compliant mesh
        # would need the twist as a state, and dropping it would change the torque.
        raise ConfigError(
            [
                "gearbox.stiffness: a compliant mesh is not in the damper FMU, whose ECD "
                "is rigid; remove gearbox.stiffness and mesh_damping to export it, or "
                "export the deployment FMU (--deployment), which runs the dynamic method"
            ],
            config.source,
        )


def build_fmu(
    config_path: str | Path,
    out: str | Path,
    deployment: bool = False,
    name: str | None = None,
) -> Path:
    """Build the FMU of the config at ``config_path`` into ``out`` (atomically); its path.

    ``name`` is the model identifier (default: derived from ``out`` and the config; see
    :func:`model_identifier`). A placeholder load gives a
    :class:`~ecdsim.config.placeholder.PlaceholderLoadWarning` and is named in the FMU's
    description. Raises :class:`~ecdsim.config.ConfigError` for a bad
    config (or, with ``deployment``, one without ``[load] inertia``, which the dynamic
    method needs), :class:`FmuNameError` for a bad name, :class:`FmuCompilerError`
    without a working C compiler (the damper FMU) and :class:`FmuDependencyError`
    without pythonfmu (the deployment FMU).
    """
    from ecdsim import __version__, atomic
    from ecdsim.config import load_config, placeholder

    config = load_config(Path(config_path))
    placeholder.warn(config)
    _check(config, deployment)
    target = Path(out)
    config_text = Path(config_path).read_bytes()
    kind = "deployment" if deployment else "damper"
    identifier = model_identifier(name, target, kind, config_text)
    guid = _guid(identifier, config_text)
    if deployment:
        data = _deployment_fmu(config, Path(config_path), identifier, guid)
    else:
        from ecdsim.fmu.model import DamperModel
        from ecdsim.fmu.native import build_damper_fmu

        data = build_damper_fmu(
            DamperModel.from_config(config),
            identifier,
            guid,
            __version__,
            _stop_time(config, deployment=False),
            config_text,
            f"Eddy current damper and gearbox at the slow shaft, from {Path(config_path).name} "
            "(ecdsim; needs no Python)"
            + (f"; {PLACEHOLDER_STOP_TIME}" if placeholder.is_placeholder(config) else ""),
        )
    return atomic.write_with(target, lambda handle: handle.write(data))


def _deployment_fmu(config: Config, config_path: Path, identifier: str, guid: str) -> bytes:
    """The deployment FMU (pythonfmu) as the bytes of its zip archive."""
    from ecdsim import __version__
    from ecdsim.config import placeholder

    try:
        from pythonfmu.builder import FmuBuilder
    except ImportError:
        from ecdsim.invocation import install_hint

        raise FmuDependencyError(
            "the deployment FMU is built with pythonfmu, which is not installed; "
            f"{install_hint('fmu')}"
        ) from None
    from ecdsim.fmu.slaves import CONFIG_FILE

    doc = "The spring-driven deployment by ecdsim's dynamic method"
    with tempfile.TemporaryDirectory(prefix="ecdsim-fmu-") as folder:
        work = Path(folder)
        source = work / "source"
        source.mkdir()
        script = source / f"{identifier}.py"
        script.write_text(
            _SCRIPT.format(name=identifier, doc=doc, version=__version__), encoding="utf-8"
        )
        shutil.copyfile(config_path, source / CONFIG_FILE)
        built_dir = work / "built"
        built_dir.mkdir()
        sys.modules.pop(identifier, None)  # the builder imports the script by its name
        try:
            built = Path(
                FmuBuilder.build_FMU(script, dest=built_dir, project_files=[source / CONFIG_FILE])
            )
        finally:
            sys.modules.pop(identifier, None)
            if str(source) in sys.path:
                sys.path.remove(str(source))
        return _finish_deployment(
            built,
            guid,
            _stop_time(config, deployment=True),
            placeholder.is_placeholder(config),
        )


def _finish_deployment(built: Path, guid: str, stop_time: float, stand_in: bool) -> bytes:
    """pythonfmu's FMU with what its modelDescription.xml lacks for FMI 2.0 hosts.

    Units, the status enumeration, a DefaultExperiment past the slowest deployment, the
    InitialUnknowns (every output: all are calculated at initialisation), ecdsim's
    version and a GUID of this export; with ``stand_in`` (a placeholder load), the
    description starts with the placeholder's title.
    """
    from ecdsim import __version__
    from ecdsim.config.placeholder import TITLE
    from ecdsim.fmu.model import STATUS_DESCRIPTIONS, STATUS_NAMES
    from ecdsim.fmu.native import UNITS, _units_element

    with zipfile.ZipFile(built) as archive:
        members = {info.filename: archive.read(info) for info in archive.infolist()}
    root = ET.fromstring(members["modelDescription.xml"])
    root.set("guid", guid)
    root.set("version", __version__)
    root.set("generationTool", f"ecdsim {__version__} with {root.get('generationTool', '')}")
    root.attrib.pop("generationDateAndTime", None)
    if stand_in:
        root.set("description", f"{TITLE}. {root.get('description', '')}".rstrip(". "))
    variables = root.find("ModelVariables")
    assert variables is not None
    outputs = []
    for index, scalar in enumerate(variables, start=1):
        name = scalar.get("name", "")
        element = scalar[0]
        if name in _DEPLOYMENT_UNITS:
            element.set("unit", _DEPLOYMENT_UNITS[name])
        if name == "status":
            scalar.remove(element)
            ET.SubElement(scalar, "Enumeration", declaredType=_STATUS_TYPE)
        if scalar.get("causality") == "output":
            outputs.append(index)
    cosimulation = root.find("CoSimulation")
    assert cosimulation is not None
    position = list(root).index(cosimulation) + 1
    used = {u for u in _DEPLOYMENT_UNITS.values() if u in UNITS}
    types = ET.Element("TypeDefinitions")
    simple = ET.SubElement(types, "SimpleType", name=_STATUS_TYPE)
    enumeration = ET.SubElement(simple, "Enumeration")
    for value, label in STATUS_NAMES.items():
        ET.SubElement(
            enumeration,
            "Item",
            name=label,
            value=str(value),
            description=STATUS_DESCRIPTIONS[value],
        )
    root.insert(position, _units_element(used))
    root.insert(position + 1, types)
    experiment = ET.Element(
        "DefaultExperiment",
        startTime="0.0",
        stopTime=repr(stop_time),
        stepSize=repr(_round_up(stop_time / 500.0)),
    )
    root.insert(list(root).index(variables), experiment)
    structure = root.find("ModelStructure")
    assert structure is not None
    initial = ET.SubElement(structure, "InitialUnknowns")
    for index in outputs:
        ET.SubElement(initial, "Unknown", index=str(index))
    ET.indent(root, space="  ")
    members["modelDescription.xml"] = (
        ET.tostring(root, encoding="UTF-8", xml_declaration=True) + b"\n"
    )
    with tempfile.TemporaryDirectory(prefix="ecdsim-fmu-") as folder:
        archive_path = Path(folder) / "out.fmu"
        with zipfile.ZipFile(archive_path, "w", zipfile.ZIP_DEFLATED) as archive:
            for member, data in members.items():
                archive.writestr(member, data)
        return archive_path.read_bytes()
