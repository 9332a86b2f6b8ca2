"""Open the samples of a finished Monte Carlo study for analysis in a notebook.

``ecdsim.montecarlo.open(folder)`` reads every chunk file of the study in ``folder``
(written by ``ecdsim montecarlo ... --out folder``) into

* a long (tidy) pandas DataFrame (default): one row per (sample, temperature), the
  sampled quantities by config key with their SI unit's suffix
  (``damper.damping_rate_Nms_per_rad``), ``temperature_C``, and the results
  (``deployment_time_s``, ``end_speed_rad_s``, ``stalled``, ``min_torque_margin``);
* an xarray Dataset (``as_="xarray"``), dimensions ``sample`` x ``temperature_C``, the
  sampled quantities over ``sample`` and the results over both, each variable with its
  unit in ``attrs["units"]`` and the study's identity in the Dataset's attributes;
* a pyarrow dataset over the chunk files (``as_="arrow"``), for studies larger than
  memory: the storage layout, one row per sample with a column per result and
  temperature (``deployment_time_s@-40.0C``; docs/montecarlo.md).

Only a finished study is opened (its ``summary.json`` written), so that no half-written
set of samples is analysed by mistake.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from ecdsim.montecarlo.columns import output_column
from ecdsim.montecarlo.store import CHUNKS, SUMMARY, ChunkReader, read_manifest, require

FORMS = ("pandas", "xarray", "arrow")
# The per-temperature results a study may hold, and their SI units (None: a flag).
RESULTS: dict[str, str | None] = {
    "deployment_time_s": "s",
    "end_speed_rad_s": "rad/s",
    "stalled": None,
    "min_torque_margin": "1",
}

LONG_NAMES = {
    "deployment_time_s": "deployment time (inf: stalled)",
    "end_speed_rad_s": "end (latch) speed (0: stalled)",
    "stalled": "stalled before the end of travel",
    "min_torque_margin": "lowest torque margin over the travel",
}


class NotAStudy(ValueError):
    """The folder holds no finished Monte Carlo study; the message says what is missing."""


@dataclass(frozen=True)
class Layout:
    """What a study's files hold, from its manifest.

    Attributes
    ----------
    temperatures : analysis temperatures [degC]
    quantities : (config key, SI unit) of each sampled quantity, in column order
    results : the per-temperature results stored (keys of :data:`RESULTS`)
    chunks : number of chunk files
    identity : the study's identity (version, config hash, method, seed, ...)
    """

    temperatures: tuple[float, ...]
    quantities: tuple[tuple[str, str], ...]
    results: tuple[str, ...]
    chunks: int
    identity: dict[str, Any]

    def quantity_column(self, key: str, unit: str) -> str:
        """The tidy column of a sampled quantity: its key and unit suffix."""
        from ecdsim.tidy import key_column

        return key_column(key, unit)


def study_layout(folder: str | Path) -> Layout:
    """The layout of the finished study in ``folder``; :class:`NotAStudy` if it is none."""
    out = Path(folder)
    if not out.is_dir():
        raise NotAStudy(f"{out}: no such folder")
    try:
        manifest = read_manifest(out)
    except ValueError as exc:
        raise NotAStudy(str(exc)) from None
    if manifest is None:
        raise NotAStudy(f"{out}: no manifest.json, not a Monte Carlo study folder")
    if not (out / SUMMARY).exists():
        raise NotAStudy(
            f"{out}: the study is not finished (no {SUMMARY}); run it to the end "
            "(ecdsim montecarlo resumes where it stopped)"
        )
    try:
        identity = dict(manifest["identity"])
        temperatures = tuple(float(t) for t in identity["temperatures_C"])
        quantities = tuple((str(t["key"]), str(t["unit"])) for t in manifest["tolerances"])
        columns = [str(c) for c in manifest["columns"]]
        chunks = int(manifest["chunks"])
    except (KeyError, TypeError, ValueError, AttributeError):
        raise NotAStudy(
            f"{out}: manifest.json does not describe a study (edited by hand?)"
        ) from None
    results = tuple(r for r in RESULTS if all(output_column(r, t) in columns for t in temperatures))
    files = sorted((out / CHUNKS).glob("chunk-*.parquet"))
    if not files or len(files) != chunks:
        raise NotAStudy(
            f"{out}: {len(files)} chunk files in {CHUNKS}/, the manifest names {chunks}"
        )
    return Layout(temperatures, quantities, results, chunks, identity)


def open_samples(folder: str | Path, as_: str = "pandas") -> Any:
    """The samples of the finished study in ``folder``: a long DataFrame, an xarray
    Dataset or a pyarrow dataset (module docstring).

    ``as_``: ``"pandas"`` (one row per sample and temperature), ``"xarray"`` (sample x
    temperature) or ``"arrow"`` (the chunk files as stored). A stalled sample's
    deployment time is ``inf``. Raises :class:`NotAStudy` for a folder without a finished
    study, ValueError naming the forms for another ``as_``, and
    :class:`~ecdsim.montecarlo.MissingDependency` when pandas, pyarrow or xarray is not
    installed (``pip install 'ecdsim[montecarlo]'``).
    """
    if not isinstance(as_, str) or as_ not in FORMS:
        raise ValueError(f"as_ = {as_!r}: expected one of {list(FORMS)}")
    layout = study_layout(folder)
    out = Path(folder)
    if as_ == "arrow":
        ds = require("pyarrow.dataset")
        files = sorted((out / CHUNKS).glob("chunk-*.parquet"))
        return ds.dataset([str(f) for f in files], format="parquet")
    if as_ == "xarray":
        return _dataset(out, layout)
    return _long_frame(out, layout)


def _columns(out: Path, layout: Layout) -> dict[str, np.ndarray[Any, Any]]:
    names = ["sample", *(key for key, _ in layout.quantities)]
    names += [output_column(r, t) for t in layout.temperatures for r in layout.results]
    return ChunkReader(out, layout.chunks).read(names)


def _long_frame(out: Path, layout: Layout) -> Any:
    """One row per (sample, temperature), samples in order, temperatures as analysed."""
    pd = require("pandas")
    require("pyarrow")
    found = _columns(out, layout)
    n_t = len(layout.temperatures)
    data: dict[str, Any] = {"sample": np.repeat(found["sample"], n_t)}
    for key, unit in layout.quantities:
        data[layout.quantity_column(key, unit)] = np.repeat(found[key], n_t)
    samples = found["sample"].size
    data["temperature_C"] = np.tile(np.asarray(layout.temperatures, dtype=float), samples)
    for result in layout.results:
        stacked = np.stack([found[output_column(result, t)] for t in layout.temperatures], axis=1)
        data[result] = stacked.reshape(-1)
    frame = pd.DataFrame(data)
    frame.attrs.update(_attributes(layout))
    return frame


def _dataset(out: Path, layout: Layout) -> Any:
    """Dimensions sample x temperature_C; units in each variable's ``attrs["units"]``."""
    xr = require("xarray")
    require("pyarrow")
    found = _columns(out, layout)
    variables: dict[str, Any] = {}
    for key, unit in layout.quantities:
        attrs = {"units": unit or "1", "config_key": key, "long_name": f"sampled {key}"}
        variables[layout.quantity_column(key, unit)] = ("sample", found[key], attrs)
    for result in layout.results:
        stacked = np.stack([found[output_column(result, t)] for t in layout.temperatures], axis=1)
        attrs = {"long_name": LONG_NAMES[result]}
        result_unit = RESULTS[result]
        if result_unit is not None:
            attrs["units"] = result_unit
        variables[result] = (("sample", "temperature_C"), stacked, attrs)
    coords = {
        "sample": ("sample", found["sample"], {"long_name": "sample index"}),
        "temperature_C": (
            "temperature_C",
            np.asarray(layout.temperatures, dtype=float),
            {"units": "degC", "long_name": "analysis temperature"},
        ),
    }
    return xr.Dataset(variables, coords=coords, attrs=_attributes(layout))


def _attributes(layout: Layout) -> dict[str, Any]:
    """The study's identity as flat attributes (netCDF-safe: numbers and strings)."""
    identity = layout.identity
    attrs: dict[str, Any] = {"ecdsim_format": "ecdsim-montecarlo/1"}
    for key in ("ecdsim_version", "config_sha256", "method", "sampling"):
        if key in identity:
            attrs[key] = str(identity[key])
    for key in ("samples", "seed", "chunk_size"):
        if key in identity:
            attrs[key] = int(identity[key])
    return attrs
