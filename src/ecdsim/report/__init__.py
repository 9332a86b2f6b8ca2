"""The self-contained HTML report of a configuration (``ecdsim report``, docs/report.md).

:mod:`~ecdsim.report.builder` collects every number from the same library calls as the
CLI (``deployment.predict``, ``Prediction.to_dict``, ``sizing.search.evaluate``) and
renders the Jinja2 template ``templates/report.html.j2`` with the figures inline;
:mod:`~ecdsim.report.pdf` prints the HTML to PDF with headless Chromium.
"""

from ecdsim.report.builder import build_context, predict_config, render_html, write_report

__all__ = ["build_context", "predict_config", "render_html", "write_report"]
