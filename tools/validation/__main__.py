"""``python -m tools.validation [OPTIONS]`` from the repository root (command.py)."""

from tools.validation.command import main

main()
