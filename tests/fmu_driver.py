"""Run an FMU with FMPy in a process of its own (tests/test_fmu.py calls this as a script).

pythonfmu's loader runs the model inside the host's Python process; after FMPy unloads
such FMUs (``simulate_fmu`` frees the library), a later garbage collection in the same
process was seen to crash (segmentation fault). Each simulation therefore runs here, in
a child process, and hands its results back in an ``.npz`` file.

Usage::

    python -m tests.fmu_driver damper FMU IN.npz OUT.npz    # IN: time, speed, ambient,
                                                            # start (names, values)
    python -m tests.fmu_driver deployment FMU IN.npz OUT.npz
"""

from __future__ import annotations

import shutil
import sys
from typing import Any

import numpy as np

DAMPER_OUTPUTS = ("damper_torque", "damper_temperature", "friction_torque")


def drive_damper(path: str, inputs: Any) -> dict[str, Any]:
    """Set the speed at each time, read the outputs there, then step to the next time."""
    import fmpy
    from fmpy.fmi2 import FMU2Slave

    md = fmpy.read_model_description(path)  # validates modelDescription.xml
    refs = {v.name: v.valueReference for v in md.modelVariables}
    folder = fmpy.extract(path)
    slave = FMU2Slave(
        guid=md.guid,
        unzipDirectory=folder,
        modelIdentifier=md.coSimulation.modelIdentifier,
        instanceName="test",
    )
    times, speeds = inputs["time"], inputs["speed"]
    names = [str(n) for n in inputs["start_names"]]
    values = [float(v) for v in inputs["start_values"]]
    outputs = []
    try:
        slave.instantiate()
        slave.setupExperiment(startTime=float(times[0]))
        slave.enterInitializationMode()
        if names:
            slave.setReal([refs[n] for n in names], values)
        slave.exitInitializationMode()
        for k, t in enumerate(times):
            slave.setReal([refs["shaft_speed"]], [float(speeds[k])])
            outputs.append(slave.getReal([refs[n] for n in DAMPER_OUTPUTS]))
            if k + 1 < len(times):
                step = float(times[k + 1] - t)
                slave.doStep(currentCommunicationPoint=float(t), communicationStepSize=step)
        slave.terminate()
    finally:
        slave.freeInstance()
        shutil.rmtree(folder, ignore_errors=True)
    got = np.array(outputs)
    return {name: got[:, i] for i, name in enumerate(DAMPER_OUTPUTS)}


def simulate_deployment(path: str, inputs: Any) -> dict[str, Any]:
    """fmpy.simulate_fmu with the given stop time, output interval and start values."""
    import fmpy

    names = [str(n) for n in inputs["start_names"]]
    values = [float(v) for v in inputs["start_values"]]
    result = fmpy.simulate_fmu(
        path,
        stop_time=float(inputs["stop_time"]),
        output_interval=float(inputs["output_interval"]),
        output=["angle", "speed", "latched"],
        start_values=dict(zip(names, values, strict=True)),
    )
    return {name: np.asarray(result[name]) for name in ("time", "angle", "speed", "latched")}


def main(argv: list[str]) -> None:
    """Entry point: ``KIND FMU IN.npz OUT.npz``."""
    kind, path, source, target = argv
    with np.load(source) as data:
        inputs = {name: data[name] for name in data.files}
    run = drive_damper if kind == "damper" else simulate_deployment
    np.savez(target, **run(path, inputs))


if __name__ == "__main__":
    main(sys.argv[1:])
