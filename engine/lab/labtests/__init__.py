"""One declaration per lab test (``TEST = LabTest(...)``), read by ``engine.lab.registry``.

A declaration is light: it imports its procedure only when the test runs.
"""
