"""Open the samples of a finished Monte Carlo study for analysis in a notebook.

``ecdsim.montecarlo.open(folder)`` reads every chunk file of the study in ``folder``
(written by ``ecdsim montecarlo ... --out folder``) into one pandas DataFrame, or gives
a pyarrow dataset over them (``as_="arrow"``) for studies too large for memory. Only a
finished study is opened (its ``summary.json`` written), so that no half-written set of
samples is analysed by mistake.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any, Literal

from ecdsim.montecarlo.store import CHUNKS, SUMMARY, read_manifest, require


class NotAStudy(ValueError):
    """The folder holds no finished Monte Carlo study; the message says what is missing."""


def open_samples(folder: str | Path, as_: Literal["pandas", "arrow"] = "pandas") -> Any:
    """The samples of the finished study in ``folder``: a DataFrame or a pyarrow dataset.

    One row per sample: its index, the sampled parameters (SI, by config key) and the
    results at each temperature (``deployment_time_s@25.0C``, ...; docs/montecarlo.md).
    Raises :class:`NotAStudy` for a folder without a finished study and
    :class:`~ecdsim.montecarlo.MissingDependency` when pandas or pyarrow is not installed
    (``pip install 'ecdsim[montecarlo]'``).
    """
    if as_ not in ("pandas", "arrow"):
        raise ValueError(f"as_ = {as_!r}: expected 'pandas' or 'arrow'")
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
    files = sorted((out / CHUNKS).glob("chunk-*.parquet"))
    if not files:
        raise NotAStudy(f"{out}: no chunk files in {CHUNKS}/")
    ds = require("pyarrow.dataset")
    dataset = ds.dataset([str(f) for f in files], format="parquet")
    if as_ == "arrow":
        return dataset
    require("pandas")
    return dataset.to_table().to_pandas()
