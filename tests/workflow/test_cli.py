"""Stage command lines: common options, number lists, logging to stderr and the log file, exit codes."""

import argparse
import logging
from dataclasses import dataclass, field

import pytest

from posefix.workflow.cli import (add_repair_option, authoring_parser, config_flags, configure_logging, dataset_docs,
                                 float_list, int_list, named_options, named_path, run_stage, stage_parser)
from posefix.io.errors import InputError


def test_number_lists():
    assert int_list("1,2, 3") == [1, 2, 3] and float_list("0.5 1") == [0.5, 1.0]
    with pytest.raises(argparse.ArgumentTypeError, match="not a list of integers"):
        int_list("1,x")


def test_named_paths():
    assert named_path("medial=results/a=b/medial.h5") == ("medial", "results/a=b/medial.h5")
    for bad in ("medial", "=x.h5", "medial="):
        with pytest.raises(argparse.ArgumentTypeError, match="not NAME=PATH"):
            named_path(bad)


def test_named_options_are_what_named_path_parses():
    import shlex
    paths = {"medial": "results/my lib/p 1/medial.h5", "other": "o.h5"}
    words = shlex.split(named_options("--repair", paths))
    assert words[::2] == ["--repair"] * 2 and dict(map(named_path, words[1::2])) == paths
    assert named_options("--repair", {}) == ""


@pytest.fixture
def posefix_logger():
    """The ``posefix`` logger as it was before the test (configure_logging changes it for the process)."""
    root = logging.getLogger("posefix")
    saved = root.handlers[:], root.level, root.propagate
    yield root
    for handler in root.handlers:
        handler.close()
    root.handlers[:], root.level, root.propagate = saved[0], saved[1], saved[2]


def test_library_loggers_reach_the_stage_log_file(tmp_path, capsys, posefix_logger):
    log = configure_logging("demo", tmp_path / "demo.log")
    logging.getLogger("posefix.verify.sequence").info("from the library")
    logging.getLogger("posefix.downstream.gauss_newton").debug("detail")
    log.info("from the stage")
    log.warning("look")
    for handler in posefix_logger.handlers:
        handler.flush()
    text = (tmp_path / "demo.log").read_text()
    assert "posefix demo: from the library" in text and "posefix demo: detail" in text
    err = capsys.readouterr().err
    assert "from the stage" in err and "detail" not in err  # DEBUG only in the file
    assert "posefix demo: warning: look" in err and "posefix demo: warning: look" in text  # the posefix command shows it
    assert log.name == "posefix.stages.demo"


@dataclass(frozen=True)
class _Settings:
    count: int = field(default=3, metadata={"help": "how many", "minimum": 1})


def test_a_stage_parser_declares_its_files_and_settings_in_one_call():
    parser = stage_parser("demo", "a test stage", [(_Settings, "counting (config demo)")], mesh_file="the mesh",
                          out="demo.h5 to write")
    args = parser.parse_args(["--mesh-file", "a.obj", "--out", "a.h5"])
    assert (args.mesh_file, args.out, args.count, args.threads, args.stage) == ("a.obj", "a.h5", 3, 1, "demo")
    with pytest.raises(SystemExit):  # a file option is required
        parser.parse_args(["--out", "a.h5"])
    assert "counting (config demo)" in parser.format_help() and "the mesh" in parser.format_help()
    add_repair_option(parser, "read it")
    assert parser.parse_args(["--mesh-file", "a", "--out", "b", "--repair", "medial=m.h5"]).repair == [("medial", "m.h5")]


def test_an_authoring_stage_names_its_library_after_its_source_file_unless_told():
    parser = authoring_parser("demo", "", [], ("rig", "rig file"), "the rig's skeleton")
    args = parser.parse_args(["--mesh", "a.obj", "--rig", "limb.yaml", "--out", "lib", "--artifact", "a.h5"])
    assert (args.mesh, args.rig, args.out, args.artifact, args.name) == ("a.obj", "limb.yaml", "lib", "a.h5", None)
    assert "default the rig file's" in " ".join(parser.format_help().split())


def test_the_dataset_docs_of_a_stage_are_its_section_of_the_artifact_schema():
    docs = dataset_docs("integrate")
    assert list(docs)[:2] == ["positions", "samples"] and docs["positions"][0] == "length"
    assert all(isinstance(units, str) and text for units, text in docs.values())
    assert "history/max_error" in dataset_docs("fit")


def _run(main, argv=()):
    parser = stage_parser("demo", "a test stage")
    with pytest.raises(SystemExit) as exit_info:
        run_stage(parser, main, list(argv))
    return exit_info.value.code


def test_errors_become_one_line_and_an_exit_code(capsys, posefix_logger):
    def bad_input(args, log):
        raise InputError("a.obj", "no faces")

    def no_disk(args, log):
        raise OSError(28, "No space left on device", "out.h5")

    assert _run(bad_input) == 2 and capsys.readouterr().err.strip().endswith("posefix demo: error: a.obj: no faces")
    assert _run(no_disk) == 1 and "error: out.h5: No space left on device" in capsys.readouterr().err
    assert stage_parser("demo", "").parse_args([]).threads == 1


def test_the_error_line_reaches_stderr_in_one_write(monkeypatch, posefix_logger):
    """With its newline: two writes (print's) let another job's line in between on the run's merged output."""
    writes = []

    class Recorder:
        def write(self, text):
            writes.append(text)

        def flush(self):
            pass

    monkeypatch.setattr("sys.stderr", Recorder())

    def bad_input(args, log):
        raise InputError("a.obj", "no faces")

    assert _run(bad_input) == 2
    assert [w for w in writes if "error:" in w or w == "\n"] == ["posefix demo: error: a.obj: no faces\n"]


def test_config_flags_are_what_the_stage_parsers_read():
    parser = argparse.ArgumentParser()
    parser.add_argument("--count", type=int)
    parser.add_argument("--align", action=argparse.BooleanOptionalAction, default=True)
    parser.add_argument("--alphas", type=float_list)
    parser.add_argument("--tracks")
    section = {"count": 11, "align": False, "alphas": [0.5, 1.0], "tracks": "my tracks.csv", "vec": None,
               "threads": 2}
    import shlex
    args = parser.parse_args(shlex.split(config_flags(section, skip=("threads", "vec"))))
    assert (args.count, args.align, args.alphas, args.tracks) == (11, False, [0.5, 1.0], "my tracks.csv")
    assert "--vec" not in config_flags(section) and "--threads" not in config_flags(section)
    with pytest.raises(TypeError, match="exclude: a dict"):
        config_flags({"exclude": {}})


def test_an_unexpected_error_reaches_the_log_file(tmp_path, capsys, posefix_logger):
    """Its one error line too (before: the posefix command said "the run failed before any stage reported" when a
    stage crashed)."""
    def bug(args, log):
        raise ZeroDivisionError("a bug")

    parser = stage_parser("demo", "a test stage")
    with pytest.raises(ZeroDivisionError):
        run_stage(parser, bug, ["--log", str(tmp_path / "demo.log")])
    for handler in posefix_logger.handlers:
        handler.flush()
    text = (tmp_path / "demo.log").read_text()
    assert "unexpected error" in text and "ZeroDivisionError: a bug" in text
    line = (f"posefix demo: error: unexpected ZeroDivisionError: a bug (a bug in posefix: please report it; its "
            f"traceback: {tmp_path / 'demo.log'})")
    assert line in text.splitlines() and line in capsys.readouterr().err.splitlines()  # the posefix command shows it
