"""Floating-frame bodies (bodies/body.py) and their builders. Importing the stage attaches the
body builder of kind mvm-sparse (bodies/ring_body.py) to its registered spec."""

from flexmvm.bodies import ring_body as _ring_body  # noqa: F401
