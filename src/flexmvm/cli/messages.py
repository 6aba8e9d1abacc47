"""The one-line messages of an interrupted or terminated command, shared by the entry point
(cli/main.py, before the command's imports) and the command (cli/app.py, during the run).
Imports nothing: main.py reads it before anything heavy is loaded."""

#: The one line of a Ctrl-C (exit status 130), during the imports and during the run.
INTERRUPTED = (
    "flexmvm: interrupted; finished study cases are kept, an unfinished run leaves "
    "its output directory as it was"
)
#: The one line of a SIGTERM (exit status 143, processes.sigterm_as_exit in app.py).
TERMINATED = (
    "flexmvm: terminated (SIGTERM); finished study cases are kept, an unfinished run "
    "leaves its output directory as it was"
)
