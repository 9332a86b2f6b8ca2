"""ecdsim's validation suite: cases against references no one in this project derived.

``python -m validation --out docs/validation.md`` (``make validate``) runs them and writes
the page; ``tests/test_validation.py`` runs the same checks in the test suite.
"""
