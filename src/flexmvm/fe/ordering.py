"""Former path of fe.solvers.ordering, kept for the modules that import it from here: this name is
the same module object (monkeypatching either patches both). New code imports
flexmvm.fe.solvers.ordering."""

import sys

from flexmvm.fe.solvers import ordering as _moved

sys.modules[__name__] = _moved
