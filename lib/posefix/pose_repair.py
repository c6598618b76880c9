"""One pose repaired in memory: the space-time repair as the pipeline's stages run it (keyframes, classify,
constraints, fit, integrate, verify), called in turn on numpy arrays, with no file. This is what a script in a DCC
calls (``posefix.repair_pose``); a whole library goes through the workflow (``posefix.repair_library``).

The settings are the pipeline's: ``config.yaml``'s sections of those stages (and ``contact``, ``summary``), with
the caller's over them, checked by the config's schema. Each stage runs with its section's ``threads`` as the BLAS
limit, as its job would, so a pose repaired here has the pipeline's vertices (``tests/test_pose_repair.py``).

Examples: ``docs/api.md``.
"""

import logging
import time
from contextlib import contextmanager
from dataclasses import dataclass

import numpy as np
import yaml
from threadpoolctl import threadpool_limits

from posefix.io.errors import InputError, PosefixError
from posefix.io.library import check_pose, check_reference, check_seams
from posefix.mesh.contacts import contact_vertices
from posefix.mesh.distortion import distortion_summary
from posefix.mesh.geometry import bbox_diagonal, unit_scale
from posefix.mesh.intersections import self_intersecting_pairs
from posefix.mesh.weld import Weld
from posefix.report.summary import verified_entry
from posefix.spacetime.classification import constraint_mask
from posefix.spacetime.constraints import spacetime_constraints
from posefix.spacetime.factorization import FactorizationError
from posefix.spacetime.fit import FitSettings, cache_fits, fit_memory, iterate, start_fit
from posefix.spacetime.integration_opencl import path_lines
from posefix.spacetime.keyframes import keyframes
from posefix.verify.sequence import finish_settings, finished_pose
from posefix.verify.state import RepairProblem
from posefix.workflow.config_check import config_problems, merged, nested
from posefix.workflow.files import workflow_folder
from posefix.workflow.resources import cache_budget, opencl_device

log = logging.getLogger(__name__)

STAGES = ("keyframes", "classify", "constraints", "fit", "integrate", "verify")
"""The pipeline's stages of a pose's space-time repair, in order: :func:`repair_pose` runs them in memory."""


@dataclass
class PoseRepair:
    """A pose repaired by :func:`repair_pose`.

    Attributes
    ----------
    V : (n, 3) float64
        The repaired positions, in the input's vertex order and units.
    status : str
        ``ok``, ``fallback`` or ``check``, as the summary's (``docs/methods.md``).
    reason : str
        Why the status is not plain ``ok`` ("" when it is).
    metrics : dict
        The verification's metrics (``verify.h5``'s in ``docs/artifacts.md``: intersecting faces of the reference,
        the target and the repair, ``repaired_new``, deviations relative to the bounding-box diagonal) and the
        repair's ``distortion`` (:func:`posefix.mesh.distortion.distortion_summary`).
    constrained : (n,) bool
        ``V_C``: the vertices the repair puts on the target.
    seconds : dict
        Wall seconds per stage of :data:`STAGES`.
    """

    V: np.ndarray
    status: str
    reason: str
    metrics: dict
    constrained: np.ndarray
    seconds: dict


def pose_settings(settings=None):
    """The pipeline's config (the workflow's ``config.yaml``) with ``settings`` over it.

    Parameters
    ----------
    settings : dict, optional
        Config sections (``{"verify": {"finish": "snap"}}``) or dotted keys (``{"verify.finish": "snap"}``).

    Returns
    -------
    dict

    Raises
    ------
    PosefixError
        A key or value the config's schema refuses, in one line naming it.
    """
    folder = workflow_folder()
    config = merged(yaml.safe_load((folder / "config.yaml").read_text()), nested(settings or {}))
    problems = config_problems(config, yaml.safe_load((folder / "schemas" / "config.schema.yaml").read_text()))
    if problems:
        raise PosefixError(f"settings: {problems[0]}")
    return config


def repair_pose(V_reference, F, V_target, settings=None):
    """Repair one pose in memory with the space-time repair and its contact finish, as the pipeline does.

    Parameters
    ----------
    V_reference : (n, 3) array_like
        The reference (intersection-free, or with intersections of its own that the repair keeps).
    F : (m, 3) array_like of int
        Triangles, the same for both.
    V_target : (n, 3) array_like
        The pose to repair.
    settings : dict, optional
        The pipeline's settings to change (:func:`pose_settings`).

    Returns
    -------
    PoseRepair

    Raises
    ------
    PosefixError
        Bad input (shapes, non-finite values, a reference the repair cannot use) or settings, in one line.
    """
    config = pose_settings(settings)
    V_ref, F, V_tgt = _checked(V_reference, F, V_target)
    weld = Weld.of(V_ref, F)
    check_seams("V_target", weld, V_tgt, V_ref, F)
    shapes, seconds = (weld.weld(V_ref), weld.weld(V_tgt), weld.faces(F)), {}
    with _stage("keyframes", config, seconds) as section:
        frames, t, _ = keyframes(*shapes, count=section["count"], align=section["align"], unwrap=section["unwrap"])
    with _stage("classify", config, seconds) as section:
        frame_pairs, mask = _classified(frames, shapes, section)
    d = bbox_diagonal(shapes[0])
    with _stage("constraints", config, seconds) as section:
        points, values, _, _ = spacetime_constraints(frames, t, mask, section["samples"], tau=section["tau"] * d,
                                                     tangents=section["tangents"])
    with _stage("fit", config, seconds) as section:
        fit = _fitted(points, values, d, section)
    with _stage("integrate", config, seconds) as section:
        samples = _path_lines(fit, shapes[0], d, config)
    with _stage("verify", config, seconds) as section:
        result = _finished(shapes, (frame_pairs, mask), (samples, frames), (d, fit), config)
    distortion = distortion_summary(result.X, {"target": shapes[1], "reference": shapes[0]}, shapes[2],
                                    config["summary"]["distortion_limit"])
    status = verified_entry(result.metrics, len(F), distortion)["status"]
    return PoseRepair(weld.unweld(result.X), status["kind"], status["reason"],
                      result.metrics | {"distortion": distortion}, mask[weld.index], seconds)


def _checked(V_reference, F, V_target):
    """``(V_ref (n, 3) float64, F (m, 3) int64, V_tgt (n, 3) float64)`` or :class:`InputError` naming the
    argument."""
    arrays = []
    for name, value, kind in (("V_reference", V_reference, np.float64), ("F", F, np.int64),
                              ("V_target", V_target, np.float64)):
        array = np.asarray(value)
        if array.ndim != 2 or array.shape[1] != 3:
            raise InputError(name, f"shape {array.shape}, expected (k, 3)")
        if kind is np.int64 and not np.issubdtype(array.dtype, np.integer):
            raise InputError(name, f"{array.dtype} indices, expected integers")
        bad = ~np.isfinite(array).all(axis=1)
        if bad.any():
            raise InputError(name, f"{bad.sum()} of {len(array)} rows with NaN or infinite values (first: row "
                                   f"{np.argmax(bad)})")
        arrays.append(np.array(array, dtype=kind))
    V_ref, F, V_tgt = arrays
    if ((F < 0) | (F >= len(V_ref))).any():
        raise InputError("F", f"a vertex index out of range 0..{len(V_ref) - 1}")
    check_reference("V_reference", V_ref, F)
    check_pose("V_target", V_tgt, F, V_ref, F)
    return V_ref, F, V_tgt


@contextmanager
def _stage(name, config, seconds):
    """Within: stage ``name``'s config section, its ``threads`` the BLAS limit; its wall seconds into ``seconds``."""
    start = time.perf_counter()
    with threadpool_limits(limits=max(1, config[name]["threads"])):
        yield config[name]
    seconds[name] = time.perf_counter() - start
    log.info("%s: %.1f s", name, seconds[name])


def _classified(frames, shapes, section):
    """``(frame_pairs, mask)``: the key frames' intersecting face pairs (list of (k, 2) int) and ``V_C`` (n,)
    bool, as stage classify (config ``classify``: ``section``; no vertex excluded by hand)."""
    V_ref, _, F = shapes
    frame_pairs = [self_intersecting_pairs(V, F) for V in frames]
    contacts = None
    if section["contact"] > 0:
        d = bbox_diagonal(V_ref)
        contacts = contact_vertices(frames, F, V_ref, section["contact"] * d, section["contact_radius"] * d)
    mask, _ = constraint_mask(F, len(V_ref), frame_pairs, ring=section["ring"], contacts=contacts)
    return frame_pairs, mask


def _fitted(points, values, d, section):
    """The greedy fit (posefix.spacetime.fit.GreedyFit) of the constraints, as stage fit (config ``fit``:
    ``section``) without its checkpoint."""
    settings = FitSettings(eps=section["eps_rel"] * d, eps_rms=section["eps_rms_rel"] * d,
                           max_centers=section["max_centers"], candidates=section["candidates"],
                           batch=section["batch"], selection=section["selection"], update=section["update"],
                           memory_bytes=cache_budget(section["memory_gb"] * 1e9, None,
                                                     fit_memory(len(points), section["max_centers"])))
    device = None if cache_fits(len(points), settings) else opencl_device(section["device"], section["threads"])[0]
    try:
        fit = start_fit(points, values, settings, device)
        iterate(fit)
    except FactorizationError as exc:
        raise InputError("V_target", str(exc)) from None
    return fit


def _path_lines(fit, V_ref, d, config):
    """The integrated path lines (S, n, 3) of the reference through the fitted field, as stage integrate."""
    section, constraints = config["integrate"], config["constraints"]
    device, _ = opencl_device(section["device"], section["threads"])
    times = np.arange(constraints["samples"] + 1) / constraints["samples"]
    _, samples, _, _ = path_lines(fit.field(), constraints["tau"] * d, V_ref, times, device,
                                  (section["rtol"], section["atol_rel"] * d, section["h0"]), section["vec"] or None)
    if not np.isfinite(samples).all():
        raise InputError("V_target", "the path lines are not finite: the fitted field is degenerate")
    return samples


def _finished(shapes, classified, paths, fitted, config):
    """The verification's RepairResult, in the input's units: the finish of config ``verify`` in the working unit
    (:func:`posefix.mesh.geometry.unit_scale`), as stage verify."""
    (V_ref, V_tgt, F), (frame_pairs, mask), (d, fit) = shapes, classified, fitted
    unit = unit_scale(V_ref)
    problem = RepairProblem.build(unit * V_ref, unit * V_tgt, F, mask, frame_pairs)
    settings = finish_settings(config["verify"] | config["contact"])
    fit_errors = (config["fit"]["eps_rel"] * d * unit, fit.history[-1]["max_error"] / d)
    result = finished_pose(problem, tuple(unit * np.asarray(p) for p in paths), unit * d, settings, fit_errors)
    result.X = result.X / unit
    return result
