"""Repository tools, run from the repository root (``python -m tools.<name>``); they import
flexmvm, flexmvm never imports them (tests/test_stages.py)."""
