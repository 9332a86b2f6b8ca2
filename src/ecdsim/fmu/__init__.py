"""FMU export (FMI 2.0 co-simulation) of the damper, or of the whole deployment.

:func:`build_fmu` writes ``EcdsimDamper.fmu`` (the ECD referred to the slow shaft:
inputs shaft speed and ambient temperature; outputs damper torque, friction torque and
damper temperature) or, with ``deployment=True``, ``EcdsimDeployment.fmu`` (the
spring-driven hinge by the dynamic method: no inputs; outputs angle, speed, latch flag).
The FMU carries the config; its parameters start at the config's values and may be
changed by the host before initialisation.

It is built with pythonfmu, an optional dependency (``pip install 'ecdsim[fmu]'``),
whose prebuilt loader (Linux x86-64 and Windows x64) runs the model in Python: the FMU
needs, at run time, a Python with ecdsim installed. Tested with FMPy (docs/fmu.md).
The physics is in :mod:`ecdsim.fmu.model`, which needs neither.
"""

from __future__ import annotations

import shutil
import sys
import tempfile
from pathlib import Path

from ecdsim.config import ConfigError

__all__ = ["FmuDependencyError", "build_fmu"]

_SCRIPT = '''"""An ecdsim FMU (see ecdsim.fmu)."""

from ecdsim.fmu.slaves import {base}


class {name}({base}):
    """{doc}"""
'''


class FmuDependencyError(ImportError):
    """pythonfmu is not installed; the message says how to install it."""


def build_fmu(config_path: str | Path, out: str | Path, deployment: bool = False) -> Path:
    """Build the FMU of the config at ``config_path`` into ``out`` (atomically); its path.

    Raises :class:`~ecdsim.config.ConfigError` for a bad config (or, with
    ``deployment``, one without ``[load] inertia``, which the dynamic method needs) and
    :class:`FmuDependencyError` without pythonfmu.
    """
    from ecdsim import atomic
    from ecdsim.api import load

    config = load(config_path)
    if deployment and config.spec.dynamics() is None:
        raise ConfigError(
            [
                "load.inertia: missing; the deployment FMU runs the dynamic method, which "
                "needs the load's moment of inertia, e.g. inertia = '5 kg*m^2' in [load]"
            ],
            config.source,
        )
    thermal = config.spec.damper.thermal
    if thermal is not None and thermal.housing_heat_capacity is not None:
        # The FMU's damper has one temperature state: a housing node would be ignored and
        # thermal_resistance (rotor to housing) misread as rotor to ambient.
        raise ConfigError(
            [
                "damper.thermal.housing_heat_capacity: two-node heating (rotor and housing) "
                "is not in the FMU, whose damper is one heat capacity; remove the housing "
                "keys to export the one-node model"
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
    try:
        from pythonfmu.builder import FmuBuilder
    except ImportError:
        raise FmuDependencyError(
            "FMU export needs pythonfmu, which is not installed; "
            "install it with: pip install 'ecdsim[fmu]'"
        ) from None
    from ecdsim.fmu.slaves import CONFIG_FILE

    if deployment:
        name, base = "EcdsimDeployment", "DeploymentSlave"
        doc = "The spring-driven deployment by ecdsim's dynamic method."
    else:
        name, base = "EcdsimDamper", "DamperSlave"
        doc = "The eddy current damper and gearbox referred to the slow shaft (ecdsim)."
    target = Path(out)
    with tempfile.TemporaryDirectory(prefix="ecdsim-fmu-") as folder:
        work = Path(folder)
        source = work / "source"
        source.mkdir()
        script = source / f"{name}.py"
        script.write_text(_SCRIPT.format(name=name, base=base, doc=doc), encoding="utf-8")
        shutil.copyfile(config_path, source / CONFIG_FILE)
        built_dir = work / "built"
        built_dir.mkdir()
        sys.modules.pop(name, None)  # the builder imports the script by its name
        try:
            built = Path(
                FmuBuilder.build_FMU(script, dest=built_dir, project_files=[source / CONFIG_FILE])
            )
        finally:
            sys.modules.pop(name, None)
            if str(source) in sys.path:
                sys.path.remove(str(source))
        data = built.read_bytes()
    return atomic.write_with(target, lambda handle: handle.write(data))
