"""Plumbing shared by the stage scripts in ``stages/``: arguments, logging, errors, threads, timers.

A stage script defines ``main(args, log)`` and ends with ``run_stage(parser, main)``. Input
problems (:class:`posefix.io.InputError`) end the stage with one line on stderr and exit code 2,
file-system errors (``OSError``) with one line and exit code 1; an interrupted stage exits 130. Outputs are written atomically by the stages, so neither leaves a
partial file behind.
"""

import argparse
import logging
import sys
import time
from contextlib import contextmanager

from threadpoolctl import threadpool_limits

from posefix.io import InputError

EXIT_INPUT_ERROR = 2


def stage_parser(stage, description):
    """An ``argparse`` parser with the options every stage has: ``--threads``, ``--log``."""
    parser = argparse.ArgumentParser(prog=f"{stage}.py", description=description,
                                     formatter_class=argparse.ArgumentDefaultsHelpFormatter)
    parser.set_defaults(stage=stage)
    parser.add_argument("--threads", type=int, default=1,
                        help="maximum BLAS/OpenMP/OpenCL threads this stage may use")
    parser.add_argument("--log", default=None, help="also append the log to this file")
    return parser


def run_stage(parser, main, argv=None):
    """Parse arguments, set up logging and thread limits, run ``main(args, log)``, map errors."""
    args = parser.parse_args(argv)
    log = _logger(args.stage, args.log)
    start = time.perf_counter()
    try:
        with threadpool_limits(limits=max(1, args.threads)):
            main(args, log)
    except InputError as exc:
        log.debug("input error", exc_info=True)
        print(f"posefix {args.stage}: error: {exc}", file=sys.stderr)
        sys.exit(EXIT_INPUT_ERROR)
    except OSError as exc:  # e.g. an output folder that cannot be created or written
        log.debug("system error", exc_info=True)
        where = f"{exc.filename}: " if exc.filename else ""
        print(f"posefix {args.stage}: error: {where}{exc.strerror or exc}", file=sys.stderr)
        sys.exit(1)
    except KeyboardInterrupt:
        print(f"posefix {args.stage}: interrupted; no output written", file=sys.stderr)
        sys.exit(130)
    log.info("done in %.2f s", time.perf_counter() - start)


def _logger(stage, path):
    log = logging.getLogger(f"posefix.{stage}")
    log.setLevel(logging.DEBUG)
    log.handlers.clear()
    log.propagate = False
    fmt = logging.Formatter(f"%(asctime)s posefix {stage}: %(message)s", datefmt="%H:%M:%S")
    console = logging.StreamHandler(sys.stderr)
    console.setLevel(logging.INFO)
    console.setFormatter(fmt)
    log.addHandler(console)
    if path:
        handler = logging.FileHandler(path, mode="w")
        handler.setLevel(logging.DEBUG)
        handler.setFormatter(fmt)
        log.addHandler(handler)
    return log


class Timings(dict):
    """Wall seconds per named sub-step; ``with timings.step("solve", log): ...`` adds and logs one."""

    @contextmanager
    def step(self, name, log=None):
        start = time.perf_counter()
        yield
        seconds = time.perf_counter() - start
        self[name] = self.get(name, 0.0) + seconds
        if log is not None:
            log.info("%s: %.3f s", name, seconds)


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
