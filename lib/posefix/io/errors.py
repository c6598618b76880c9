"""posefix's exceptions: :class:`PosefixError`, whose message is one line; :class:`InputError` for a problem with
user input."""


class PosefixError(Exception):
    """What the Python API (``posefix.repair_pose``, ``posefix.repair_library``) raises: its message is the one line
    that says what failed and where (the file, key or argument), as the ``posefix`` command prints it."""


class InputError(PosefixError):
    """A problem with user input, reported as ``<path>: <problem>``.

    Stage command lines (:func:`posefix.workflow.cli.run_stage`) print it as one line and exit 2.
    """

    def __init__(self, path, problem):
        super().__init__(f"{path}: {problem}")
        self.path, self.problem = str(path), problem


def one_line(exc):
    """The first line of an exception's message (at most 200 characters), or its type's name (str), for an
    :class:`InputError` built from a library's exception."""
    text = str(exc).strip().splitlines()
    return (text[0] if text else type(exc).__name__)[:200]
