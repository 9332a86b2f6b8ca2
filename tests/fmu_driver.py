"""Run an FMU with FMPy in a process of its own (tests/test_fmu.py calls this as a script).

It imports FMPy and NumPy only, never ecdsim, so that it runs as well in a Python that
has FMPy and nothing of ecdsim (the damper FMU needs no Python; tests/test_fmu.py makes
such a venv) as in the test environment. Each command reads a JSON file and writes its
results as JSON:

    python tests/fmu_driver.py validate FMU OUT.json
    python tests/fmu_driver.py cosim FMU IN.json OUT.json      # drive doStep by doStep
    python tests/fmu_driver.py simulate FMU IN.json OUT.json   # fmpy.simulate_fmu
    python tests/fmu_driver.py instances FMU IN.json OUT.json  # several live instances

The deployment FMU runs Python inside the process that loads it (pythonfmu); running it
here keeps the test process apart from that.
"""

from __future__ import annotations

import json
import shutil
import sys
import tempfile
from typing import Any

import numpy as np


def _slave(path: str, folder: str, name: str) -> tuple[Any, dict[str, int]]:
    import fmpy
    from fmpy.fmi2 import FMU2Slave

    md = fmpy.read_model_description(path)
    refs = {v.name: v.valueReference for v in md.modelVariables}
    slave = FMU2Slave(
        guid=md.guid,
        unzipDirectory=folder,
        modelIdentifier=md.coSimulation.modelIdentifier,
        instanceName=name,
    )
    return slave, refs


def _start(slave: Any, refs: dict[str, int], start: dict[str, float]) -> None:
    slave.instantiate()
    slave.setupExperiment(startTime=0.0)
    slave.enterInitializationMode()
    if start:
        slave.setReal([refs[n] for n in start], [float(v) for v in start.values()])
    slave.exitInitializationMode()


def cosim(path: str, inputs: dict[str, Any]) -> dict[str, Any]:
    """Set the inputs at each time, read the outputs there, then step to the next time."""
    import fmpy

    folder = fmpy.extract(path)
    slave, refs = _slave(path, folder, "driven")
    times = inputs["time"]
    names = list(inputs["inputs"])
    outputs = list(inputs["outputs"])
    rows = []
    try:
        _start(slave, refs, inputs.get("start", {}))
        for k, t in enumerate(times):
            values = [float(inputs["inputs"][n][k]) for n in names]
            slave.setReal([refs[n] for n in names], values)
            rows.append(slave.getReal([refs[n] for n in outputs]))
            if k + 1 < len(times):
                slave.doStep(
                    currentCommunicationPoint=float(t),
                    communicationStepSize=float(times[k + 1] - t),
                )
        slave.terminate()
    finally:
        slave.freeInstance()
        shutil.rmtree(folder, ignore_errors=True)
    table = np.array(rows)
    return {name: table[:, i].tolist() for i, name in enumerate(outputs)}


def simulate(path: str, inputs: dict[str, Any]) -> dict[str, Any]:
    """fmpy.simulate_fmu with the given keyword arguments (``input`` given as columns)."""
    import fmpy

    kwargs = dict(inputs["kwargs"])
    if "input" in kwargs:
        columns = kwargs["input"]
        kwargs["input"] = np.array(
            list(zip(*columns.values(), strict=True)),
            dtype=[(name, np.float64) for name in columns],
        )
    result = fmpy.simulate_fmu(path, **kwargs)
    return {name: np.asarray(result[name]).astype(float).tolist() for name in result.dtype.names}


def instances(path: str, inputs: dict[str, Any]) -> dict[str, Any]:
    """Several live instances at once, stepped in turn; each one's outputs at each step.

    ``inputs["runs"]`` lists, per instance, its start values and input columns (the same
    times for all); the instances are instantiated together and stepped interleaved, then
    run again one at a time, after repeated ``simulate_fmu`` calls of the same FMU in this
    process (``inputs["simulations"]`` of them).
    """
    import fmpy

    out: dict[str, Any] = {"simulations": []}
    for _ in range(int(inputs.get("simulations", 0))):
        result = fmpy.simulate_fmu(path)  # the DefaultExperiment
        out["simulations"].append(np.asarray(result[inputs["outputs"][0]]).astype(float).tolist())
    folder = tempfile.mkdtemp()
    shutil.rmtree(folder)
    folder = fmpy.extract(path, unzipdir=folder)
    times = inputs["time"]
    outputs = list(inputs["outputs"])

    def run(slaves: list[tuple[Any, dict[str, int], dict[str, Any]]]) -> list[list[list[float]]]:
        got: list[list[list[float]]] = [[] for _ in slaves]
        for k, t in enumerate(times):
            for i, (slave, refs, spec) in enumerate(slaves):
                names = list(spec.get("inputs", {}))
                if names:
                    slave.setReal(
                        [refs[n] for n in names], [float(spec["inputs"][n][k]) for n in names]
                    )
                got[i].append(slave.getReal([refs[n] for n in outputs]))
            if k + 1 < len(times):
                for slave, _, _ in slaves:
                    slave.doStep(
                        currentCommunicationPoint=float(t),
                        communicationStepSize=float(times[k + 1] - t),
                    )
        return got

    try:
        together = []
        for i, spec in enumerate(inputs["runs"]):
            slave, refs = _slave(path, folder, f"together{i}")
            _start(slave, refs, spec.get("start", {}))
            together.append((slave, refs, spec))
        out["together"] = run(together)
        for slave, _, _ in together:
            slave.terminate()
            slave.freeInstance()
        alone = []
        for i, spec in enumerate(inputs["runs"]):
            slave, refs = _slave(path, folder, f"alone{i}")
            _start(slave, refs, spec.get("start", {}))
            alone.append(run([(slave, refs, spec)])[0])
            slave.terminate()
            slave.freeInstance()
        out["alone"] = alone
    finally:
        shutil.rmtree(folder, ignore_errors=True)
    return out


def main(argv: list[str]) -> None:
    """Entry point: ``COMMAND FMU [IN.json] OUT.json``."""
    command, path = argv[0], argv[1]
    if command == "validate":
        import fmpy.validation

        result: Any = {"problems": fmpy.validation.validate_fmu(path)}
        target = argv[2]
    else:
        with open(argv[2], encoding="utf-8") as handle:
            inputs = json.load(handle)
        target = argv[3]
        run = {"cosim": cosim, "simulate": simulate, "instances": instances}[command]
        result = run(path, inputs)
        # The deployment FMU's Python runs in this interpreter (pythonfmu): did it load numba?
        result["numba_loaded"] = "numba" in sys.modules
    try:
        import ecdsim  # noqa: F401
    except ImportError:
        result["ecdsim_importable"] = False
    else:
        result["ecdsim_importable"] = True
    with open(target, "w", encoding="utf-8") as handle:
        json.dump(result, handle)


if __name__ == "__main__":
    main(sys.argv[1:])
