"""The one exception type for problems with user input."""


class InputError(Exception):
    """A problem with user input, reported as ``<path>: <problem>``.

    Stage command lines (:func:`posefix.workflow.cli.run_stage`) print it as one line and exit 2.
    """

    def __init__(self, path, problem):
        super().__init__(f"{path}: {problem}")
        self.path, self.problem = str(path), problem
