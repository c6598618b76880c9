"""Input errors name the file and the problem on one line."""

from posefix.io.errors import InputError


def test_message_names_the_file_and_the_problem():
    exc = InputError("lib/a.obj", "no vertices")
    assert str(exc) == "lib/a.obj: no vertices" and (exc.path, exc.problem) == ("lib/a.obj", "no vertices")
