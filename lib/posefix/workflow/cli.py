"""Plumbing shared by the stage scripts in ``stages/``: arguments, logging, errors, threads.

A stage script defines ``main(args, log)`` and ends with ``run_stage(parser, main)``. Input
problems (:class:`posefix.io.errors.InputError`) end the stage with one line on stderr and
exit code 2, file-system errors (``OSError``) with one line and exit code 1; an interrupted stage
exits 130. Outputs are written atomically by the stages, so neither leaves a partial file behind.

Logging is configured here, once per stage process, on the ``posefix`` logger: INFO and above on
stderr, everything (DEBUG too) in the ``--log`` file. Library modules log through
``logging.getLogger(__name__)`` and so reach both; the stage itself gets ``posefix.stages.<stage>``.
"""

import argparse
import functools
import inspect
import logging
import os
import shlex
import signal
import sys
import time
from pathlib import Path

import yaml
from threadpoolctl import threadpool_limits

from posefix.io.errors import InputError
from posefix.workflow.files import workflow_folder
from posefix.workflow.settings import add_settings_options

_LOADER = getattr(yaml, "CSafeLoader", yaml.SafeLoader)

EXIT_INPUT_ERROR = 2


class StageHelpFormatter(argparse.ArgumentDefaultsHelpFormatter):
    """``--help`` with each option's default said once, where there is one: none for required options, options
    without a default or whose help already names it; ``(on by default)`` / ``(off by default)`` for switches."""

    def _get_help_string(self, action):
        text = (action.help or "").replace(" (default: %(default)s)", "")  # Python 3.11's switches add it
        if isinstance(action, argparse.BooleanOptionalAction):
            return f"{text} ({'on' if action.default else 'off'} by default)"
        default = action.default
        unsaid = any(default is none for none in (None, argparse.SUPPRESS, False)) or default in ([], "")
        if action.required or unsaid or "default" in text:
            return text
        return f"{text} (default: %(default)s)"


def stage_parser(stage, description, settings=(), **files):
    """An ``argparse`` parser with the options every stage has (``--threads``, ``--log``) and the stage's own.

    Parameters
    ----------
    stage : str
        The stage's name (``<stage>.py`` in the usage line).
    description : str
        The stage's docstring.
    settings : sequence of (dataclass, str)
        Option groups: a settings class (one option per field, :func:`posefix.workflow.settings.add_settings_options`)
        and the group's title.
    **files : str
        The stage's required options, ``--name`` (underscores as dashes), each with its help, in the order given:
        the files it reads and writes (``out``), mostly.

    Returns
    -------
    argparse.ArgumentParser
        The stage's further options are added by the caller.
    """
    parser = argparse.ArgumentParser(prog=f"{stage}.py", description=description,
                                     formatter_class=StageHelpFormatter)
    parser.set_defaults(stage=stage)
    parser.add_argument("--threads", type=int, default=1,
                        help="maximum BLAS/OpenMP/OpenCL threads this stage may use")
    parser.add_argument("--log", default=None, help="also append the log to this file")
    for name, text in files.items():
        parser.add_argument("--" + name.replace("_", "-"), required=True, help=text)
    for cls, title in settings:
        add_settings_options(parser, cls, title)
    return parser


def authoring_parser(stage, description, settings, source, artifact):
    """The parser of a stage that authors a pose library from a reference mesh (:func:`stage_parser`): ``--mesh``,
    the file of the poses, ``--out`` (the library's folder), ``--artifact`` and ``--name``.

    Parameters
    ----------
    stage, description, settings
        As for :func:`stage_parser`.
    source : (str, str)
        The option naming the file the poses come from (a rig, a pose script, marker tracks) and its help; the
        library is named after that file unless ``--name`` is given.
    artifact : str
        What the HDF5 file ``--artifact`` holds.

    Returns
    -------
    argparse.ArgumentParser
    """
    option, text = source
    parser = stage_parser(stage, description, settings, mesh="reference mesh (.obj/.ply/.off, optionally .gz)",
                          **{option: text}, out="folder of the authored pose library",
                          artifact=f"HDF5 file of {artifact}")
    parser.add_argument("--name", default=None, help=f"library name, the start of its files' names "
                                                     f"(<name>-reference.*); default the {option} file's")
    return parser


@functools.cache
def dataset_docs(stage):
    """Units and description of every dataset of ``stage``'s artifact, from ``schemas/artifacts.yaml`` (their one
    description; ``write_artifact`` stores them as the datasets' attributes).

    Parameters
    ----------
    stage : str

    Returns
    -------
    dict of str -> (str, str)
        Dataset name -> (units, description), in the order the stage writes them.
    """
    path = workflow_folder() / "schemas" / "artifacts.yaml"
    with open(path, encoding="utf-8") as fh:
        return {name: tuple(doc) for name, doc in yaml.load(fh, Loader=_LOADER)[stage].items()}


def run_stage(parser, main, argv=None):
    """Parse arguments, set up logging and thread limits, run ``main(args, log)``, map errors."""
    args = parser.parse_args(argv)
    signal.signal(signal.SIGINT, signal.default_int_handler)  # from here KeyboardInterrupt, handled below
    log = configure_logging(args.stage, args.log)
    start = time.perf_counter()
    try:
        with threadpool_limits(limits=max(1, args.threads)):
            main(args, log)
    except InputError as exc:
        log.debug("input error", exc_info=True)
        _say_error(f"posefix {args.stage}: error: {exc}")
        sys.exit(EXIT_INPUT_ERROR)
    except OSError as exc:  # e.g. an output folder that cannot be created or written
        log.debug("system error", exc_info=True)
        where = f"{exc.filename}: " if exc.filename else ""
        _say_error(f"posefix {args.stage}: error: {where}{exc.strerror or exc}")
        sys.exit(1)
    except KeyboardInterrupt:
        print(f"posefix {args.stage}: interrupted; no output written", file=sys.stderr)
        sys.exit(130)
    except Exception as exc:  # a bug: one line, then the traceback to stderr (Python's) and to the log file
        log.debug("unexpected error", exc_info=True)
        where = f"; its traceback: {args.log}" if args.log else ""
        _say_error(f"posefix {args.stage}: error: unexpected {type(exc).__name__}: {exc} (a bug in posefix: please "
                   f"report it{where})")
        raise
    log.info("done in %.2f s", time.perf_counter() - start)


def _say_error(line):
    """Print a stage's one error ``line`` to stderr and write it, as it is, to the stage's log file (where plain
    ``snakemake`` finds it to repeat it at the end of a failed run). One write of the line with its newline: an
    unbuffered stderr gets print's two (line, newline), and another job's line then came in between on the run's
    merged output (a loaded `make test` saw "... (OBJ indices start at 1)23:20:50 posefix skeleton: ...")."""
    sys.stderr.write(line + "\n")
    sys.stderr.flush()
    for handler in logging.getLogger("posefix").handlers:
        if isinstance(handler, logging.FileHandler):
            handler.stream.write(line + "\n")
            handler.flush()


def configure_logging(stage, path=None):
    """Send the ``posefix`` loggers to stderr (INFO) and to ``path`` (DEBUG); the stage's own logger.

    Parameters
    ----------
    stage : str
        Stage name, in every line (``HH:MM:SS posefix <stage>: message``).
    path : str, optional
        Log file, rewritten.

    Returns
    -------
    logging.Logger
        ``posefix.stages.<stage>``.
    """
    root = logging.getLogger("posefix")
    root.setLevel(logging.DEBUG)
    root.handlers.clear()
    root.propagate = False
    fmt = logging.Formatter(f"%(asctime)s posefix {stage}: %(level)s%(message)s", datefmt="%H:%M:%S")
    console = logging.StreamHandler(sys.stderr)
    console.setLevel(logging.INFO)
    handlers = [console] + ([logging.FileHandler(path, mode="w")] if path else [])
    for handler in handlers:
        handler.setFormatter(fmt)
        handler.addFilter(_level_word)
        root.addHandler(handler)
    handlers[-1].setLevel(logging.DEBUG if path else logging.INFO)
    return logging.getLogger(f"posefix.stages.{stage}")


def _level_word(record):
    """Logging filter: ``record.level`` is ``"warning: "`` for warnings and above (the posefix command shows those
    lines on the terminal), empty otherwise; keeps every record."""
    record.level = "warning: " if record.levelno >= logging.WARNING else ""
    return True


def library_defaults(obj):
    """Parameter name -> default of a function, or of a (data)class's constructor; parameters without one left out.

    Stages take their argparse defaults from here, so that they are the library's (which
    ``tests/test_defaults.py`` compares with config.yaml).
    """
    return {name: p.default for name, p in inspect.signature(obj).parameters.items() if p.default is not p.empty}


def int_list(text):
    """Parse ``"1,2, 3"`` into ``[1, 2, 3]`` (argparse type)."""
    return _number_list(text, int, "integers")


def float_list(text):
    """Parse ``"0.5,1"`` into ``[0.5, 1.0]`` (argparse type)."""
    return _number_list(text, float, "numbers")


def _number_list(text, kind, name):
    try:
        return [kind(x) for x in text.replace(",", " ").split()]
    except ValueError:
        raise argparse.ArgumentTypeError(f"not a list of {name}: {text!r}") from None


def named_path(text):
    """Parse ``"medial=results/lib/p/medial.h5"`` into ``("medial", "results/lib/p/medial.h5")`` (argparse type)."""
    name, sep, path = text.partition("=")
    if not (sep and name and path):
        raise argparse.ArgumentTypeError(f"not NAME=PATH: {text!r}")
    return name, path


def config_flags(section, skip=("threads",)):
    """A stage's command-line options from its config section (the one way the rules turn config into flags).

    ``key: value`` becomes ``--key-name value``; a boolean ``--key-name`` or ``--no-key-name``; a list its
    items joined by commas (:func:`int_list`, :func:`float_list`); None is left out (the stage's default). Keys
    of ``skip`` are not options (threads are the rule's).

    Parameters
    ----------
    section : dict
        The config section, e.g. ``config["keyframes"]``.
    skip : sequence of str

    Returns
    -------
    str
        Shell-quoted options.

    Examples
    --------
    >>> config_flags({"count": 11, "align": False, "alphas": [0.5, 1.0], "device": "auto", "threads": 2})
    '--count 11 --no-align --alphas 0.5,1.0 --device auto'
    """
    flags = []
    for key, value in section.items():
        name = "--" + key.replace("_", "-")
        if key in skip or value is None:
            continue
        if isinstance(value, bool):
            flags.append(name if value else "--no-" + name[2:])
        elif isinstance(value, (list, tuple)):
            flags += [name, shlex.quote(",".join(map(str, value)))]
        elif isinstance(value, dict):
            raise TypeError(f"{key}: a dict is no command-line option; skip it and pass it otherwise")
        else:
            flags += [name, shlex.quote(str(value))]
    return " ".join(flags)


def put_interpreter_first_on_path():
    """Put the folder of the running interpreter first on ``PATH`` (the workflow's rules call ``python``: the
    interpreter that runs Snakemake, e.g. a venv's, unless a conda environment of the rule comes first)."""
    os.environ["PATH"] = os.pathsep.join([str(Path(sys.executable).parent), os.environ.get("PATH", "")])


def add_repair_option(parser, use):
    """Add the repeatable option ``--repair NAME=PATH`` (another repair's artifact of the pose, :func:`named_path`) to
    ``parser`` (argparse.ArgumentParser); ``use`` (str) says what the stage does with it."""
    parser.add_argument("--repair", type=named_path, action="append", default=[], metavar="NAME=PATH",
                        help=f"another repair's artifact (e.g. medial=<pose>/medial.h5): {use}; repeatable")


def named_options(option, paths):
    """Shell-quoted command-line options ``<option> <name>=<path>`` for ``paths`` {name: path}, str (what
    :func:`named_path` parses; the rules pass the other repairs' artifacts to the stages with it)."""
    return " ".join(f"{option} {shlex.quote(f'{name}={path}')}" for name, path in paths.items())
