"""The downstream check (S0 §5): does a Gauss–Newton discrete-shell solver converge better on the repaired pose?

Example-driven deformation (Fröhlich & Botsch 2011) of the reference towards the original target
and towards the repaired pose (and, optionally, the poses of other repairs), over a grid of
interpolation weights alpha and bending stiffnesses k_b (single settings are fragile). The same
far-apart handle vertices are pinned at their linear blend in every run.
"""

import itertools
import logging
from contextlib import nullcontext
from dataclasses import dataclass

import numpy as np
from threadpoolctl import threadpool_limits

from posefix.downstream.gauss_newton import STOP_REASONS, gauss_newton
from posefix.mesh.shells import mesh_hinges, shell_energy
from posefix.workflow.processes import ordered_map

log = logging.getLogger(__name__)

EXAMPLES = ("original", "repaired")
"""The two examples of S0's downstream check (S0 §5): codes 0 and 1 of downstream.h5's ``example``;
the other repairs checked beside them follow (downstream.h5's ``examples`` names every code)."""

GRID = {"alphas": [0.5, 1.0], "k_bend": [1e-3, 1e-2, 1e-1]}
"""The grid of six settings (alpha x k_b) to compare original and repaired poses over, as single settings are
fragile (a run that converges at one k_b can collapse a triangle at the next): ``make bench``'s choice, config
``downstream`` as an option; the default is its one setting alpha 1, k_b 1e-2 (a sixth of the time)."""

SPAWN_MIN_VERTICES = 1000
"""Meshes with fewer vertices run their grid in the calling process whatever ``workers`` asks: starting a worker
(a Python process importing numpy and scipy, about 1 s on 2 cores) costs more than their runs (a 162-vertex
sphere's two runs take 0.2 s)."""


def handle_vertices(V, count=3):
    """``count`` far-apart vertices of ``V`` (n, 3) float by farthest-point sampling, (count,) int64.

    Starts from the vertex farthest from the centroid; deterministic (ties: lowest index).
    """
    chosen = [int(np.argmax(np.linalg.norm(V - V.mean(axis=0), axis=1)))]
    dist = np.linalg.norm(V - V[chosen[0]], axis=1)
    while len(chosen) < count:
        chosen.append(int(np.argmax(dist)))
        dist = np.minimum(dist, np.linalg.norm(V - V[chosen[-1]], axis=1))
    return np.array(chosen, dtype=np.int64)


def deform_towards(V_ref, F, V_example, alpha, k_bend, k_stretch=1.0, settings=None, hinges=None):
    """Example-driven deformation of ``V_ref`` (n, 3) float towards ``alpha`` of ``V_example`` (n, 3).

    Starts from the reference with three far-apart vertices (:func:`handle_vertices`) pinned at their linear
    blend ``(1 - alpha) V_ref + alpha V_example`` and runs :func:`gauss_newton` on :func:`shell_energy`
    (``hinges``: :func:`posefix.mesh.shells.mesh_hinges` of ``F``, when already built). Returns its
    :class:`SolveResult`.
    """
    h = handle_vertices(V_ref)
    energy = shell_energy(V_ref, F, V_example, alpha, k_bend, k_stretch, hinges)
    pinned = (1.0 - alpha) * V_ref[h] + alpha * V_example[h]
    return gauss_newton(energy, V_ref, h, pinned, F, settings)


@dataclass
class DownstreamCheck:
    """The runs of :func:`downstream_check`: ``grid`` (alpha, k_b, example code) and a
    :class:`~posefix.downstream.gauss_newton.SolveResult` per run, in the same order, the ``handles`` and
    the ``examples``' names (index: example code)."""

    grid: list
    runs: list
    handles: np.ndarray
    examples: tuple = EXAMPLES

    def datasets(self):
        """The arrays of ``downstream.h5`` (``docs/artifacts.md``), dict of str -> ndarray."""
        grid, runs = self.grid, self.runs
        return {
            "alpha": np.array([g[0] for g in grid]), "k_bend": np.array([g[1] for g in grid]),
            "example": np.array([g[2] for g in grid], dtype=np.uint8),
            "iterations": np.array([r.iterations for r in runs], dtype=np.int64),
            "converged": np.array([r.converged for r in runs]),
            "reason": np.array([STOP_REASONS.index(r.reason) for r in runs], dtype=np.uint8),
            "final_error": np.array([r.errors[-1] for r in runs]),
            "gradient_reduction": np.array([r.gradient_reduction for r in runs]),
            "min_area_ratio": np.array([r.min_area_ratio for r in runs]),
            "seconds": np.array([r.seconds for r in runs]),
            "errors": np.concatenate([r.errors for r in runs]),
            "error_offsets": np.cumsum([0] + [len(r.errors) for r in runs]).astype(np.int64),
            "handles": self.handles, "examples": np.array(self.examples)}

    def metrics(self):
        """Converged runs and iterations per example (``<example>_converged``, ``<example>_iterations``), ``runs``."""
        out = {}
        for example, name in enumerate(self.examples):
            sel = [r for g, r in zip(self.grid, self.runs) if g[2] == example]
            out[f"{name}_converged"] = int(sum(r.converged for r in sel))
            out[f"{name}_iterations"] = int(sum(r.iterations for r in sel))
        out["runs"] = len(self.grid)
        return out

    def curves(self):
        """One dict per run for :func:`posefix.report.figures.downstream_history`."""
        return [{"alpha": a, "k_bend": k, "example": self.examples[e], "errors": r.errors, "converged": r.converged,
                 "reason": r.reason} for (a, k, e), r in zip(self.grid, self.runs)]


def downstream_check(V_ref, F, examples, alphas=(1.0,), k_bend=(1e-2,), k_stretch=1.0,
                     settings=None, workers=1):
    """Deform the reference towards every example over the grid alpha x k_b (S0 §5).

    Parameters
    ----------
    V_ref : (n, 3) float
    F : (m, 3) int
    examples : dict of str -> (n, 3) float
        The poses to deform towards, in the order of their example codes: :data:`EXAMPLES`
        (``original``: the target, ``repaired``), then any other repairs by name.
    alphas, k_bend : sequence of float
        Interpolation weights and bending stiffnesses of the grid: one setting by default, :data:`GRID` for the
        robust comparison (single settings are fragile).
    k_stretch : float
    settings : posefix.downstream.gauss_newton.SolverSettings, optional
    workers : int
        Runs at a time, each in a process of its own with one BLAS thread: the same runs as one after
        the other (iterations, stop reasons; bit for bit on the demo, but runs that end in a collapsed
        triangle can differ in the last bits, reports/bench/downstream.md). The processes are spawned: a calling script needs the
        ``if __name__ == "__main__":`` guard. On Linux they die with the calling process, however it dies. A mesh
        under :data:`SPAWN_MIN_VERTICES` vertices runs in the calling process, with one BLAS thread as a worker.

    Returns
    -------
    DownstreamCheck
        Runs in the order alpha, then k_b, then example.
    """
    hinges, handles, names = mesh_hinges(F), handle_vertices(V_ref), tuple(examples)
    grid = list(itertools.product(alphas, k_bend, range(len(names))))
    jobs = [(V_ref, F, examples[names[example]], alpha, kb, k_stretch, settings, hinges)
            for alpha, kb, example in grid]
    runs = []
    in_process = workers > 1 and len(V_ref) < SPAWN_MIN_VERTICES
    with threadpool_limits(1) if in_process else nullcontext():  # one BLAS thread, as a worker: the same bits
        for i, ((alpha, kb, example), res) in enumerate(
                zip(grid, ordered_map(deform_towards, jobs, 1 if in_process else workers)), 1):
            log.info("[%d/%d] alpha %g k_b %g %-8s: %3d iterations, %s, E %.3g (%.1f s)", i, len(grid), alpha, kb,
                     names[example], res.iterations, res.reason, res.errors[-1], res.seconds)
            runs.append(res)
    check = DownstreamCheck(grid, runs, handles, names)
    metrics = check.metrics()
    for example, name in enumerate(names):
        log.info("%s: converged in %d of %d runs, %d iterations in all", name, metrics[f"{name}_converged"],
                 sum(g[2] == example for g in grid), metrics[f"{name}_iterations"])
    return check


