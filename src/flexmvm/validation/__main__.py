"""``python -m flexmvm.validation [OPTIONS]``: the same as ``flexmvm validate [OPTIONS]``
(cli/validate_cmd.py), kept for the README and docs that call it so. An entry point, above
every stage, like the ``flexmvm`` command itself."""

import sys

from flexmvm.cli.main import main

main(["validate", *sys.argv[1:]])
