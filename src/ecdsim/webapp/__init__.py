"""The local explorer (``ecdsim app``): a JSON HTTP API with OpenAPI docs and a web page.

The server lives in :mod:`ecdsim.webapp.server` and needs the optional ``app`` extra
(FastAPI, uvicorn, plotly for plotly.js); importing this package alone needs none of them.
"""
