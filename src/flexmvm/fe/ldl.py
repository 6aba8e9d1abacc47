"""Former path of fe.solvers.ldl, kept for the modules that import it from here: this name is
the same module object (monkeypatching either patches both). New code imports
flexmvm.fe.solvers.ldl."""

import sys

from flexmvm.fe.solvers import ldl as _moved

sys.modules[__name__] = _moved
