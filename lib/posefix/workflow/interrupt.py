"""Ctrl-C in a stage ends it quietly with exit status 130, also while its (slow) imports run.

Imported first by every stage script (it also applies the package's runtime defaults, importing
``posefix``): until :func:`posefix.workflow.cli.run_stage` takes over, SIGINT ends the process with one
line and no traceback. Not for library use: it replaces the interpreter's SIGINT handler.
"""

import signal
import sys


def _interrupted(signum, frame):
    print(f"posefix {sys.argv[0].rsplit('/', 1)[-1].removesuffix('.py')}: interrupted; no output written",
          file=sys.stderr)
    sys.exit(130)


signal.signal(signal.SIGINT, _interrupted)
