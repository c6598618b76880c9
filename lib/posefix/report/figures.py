"""Report figures: one function per figure, from arrays to a matplotlib ``Figure`` (no pyplot state).

Lengths are relative to the reference's bounding-box diagonal ``d`` wherever a figure shows them.
The stage scripts (``stages/render.py``, ``stages/overview.py``) write the figures as PNG.
"""

import numpy as np
from matplotlib import colormaps
from matplotlib.cm import ScalarMappable
from matplotlib.colors import to_rgb
from matplotlib.figure import Figure
from matplotlib.patches import Patch

from posefix.verify.flags import (CONTACT, FLAGS, PUSHED, REPLACED_NEW_INTERSECTION, REPLACED_PASS_THROUGH,
                                  RIGID_REFERENCE, SEPARATED, SMOOTHED)
from posefix.report.contents import SPACETIME
from posefix.report.rasterizer import DISTORTED, HIGHLIGHT, SECONDARY, draw_mesh, face_values, heat_colors, view_limits
from posefix.report.tables import DEVIATION_BAR, repair_names, converged_runs, downstream_counts

DPI = 110
FLAG_COLORS = {REPLACED_PASS_THROUGH: "tab:red", REPLACED_NEW_INTERSECTION: "tab:orange", SMOOTHED: "tab:green",
               RIGID_REFERENCE: "tab:purple", PUSHED: "tab:blue", SEPARATED: "tab:brown", CONTACT: "tab:cyan"}
"""Colour of the vertices of each flag in the deviation figure (the snap's ``REPRODUCED`` is not drawn)."""
EXAMPLE_STYLES = {"original": "--", "repaired": "-"}
"""Line style of the downstream runs per example; the other repairs' are dotted."""
DEVIATION_MARKERS = (("constrained_max", "o", "V_C max"), ("constrained_mean", "s", "V_C mean"),
                     ("free_max", "^", "free max"))
"""Deviation summaries in the library overview: key, marker, label."""
REPAIR_COLORS = ("tab:cyan", "tab:olive", "tab:brown")
"""Colour of each other repair (in ``summary.json``'s order) in the library overview."""
CONSTRAINED = (0.25, 0.45, 0.85)
"""Colour of the faces of ``V_C`` (all three corners constrained) in the classification figure and the viewer."""
FREE = (0.85, 0.85, 0.85)
"""Colour of the other faces (free: integrated through the field) there."""
HEAT_MAP = "magma_r"
"""Colour map of the deviation heat map (figure and viewer)."""


def heat_limit(deviation):
    """Top of the deviation heat map's colour scale: the 99.5th percentile of ``deviation`` (n,), or its max when
    that is 0, float (the figure and the viewer colour a pose on the same scale)."""
    return float(np.percentile(deviation, 99.5)) or float(deviation.max())


def panel_height(limits, width=4.6, extra=1.8):
    """Figure height (inches) for mesh panels ``width`` inches wide showing ``limits`` (2, 2), plus titles."""
    aspect = (limits[1, 1] - limits[1, 0]) / (limits[0, 1] - limits[0, 0])
    return float(np.clip(width * aspect + extra, 3.0, 9.0))


def renders(F, R, poses, reference_faces, title="", distorted=None):
    """A target and its repairs side by side, intersecting faces highlighted (S0 Fig. 6 style).

    Parameters
    ----------
    F : (m, 3) int
    R : (3, 3) float
        Camera (:func:`posefix.report.rasterizer.camera`).
    poses : dict of str -> ((n, 3) float, (m,) bool)
        Panel title -> positions and intersecting faces: the target first, then the repaired poses, one panel
        each, on one scale.
    reference_faces : (m,) bool
        Faces intersecting in the reference.
    title : str
    distorted : list of (m,) bool, optional
        Distorted faces of each repaired pose, in order: drawn in purple, counted in the titles
        (:func:`posefix.mesh.distortion.distorted_faces`).

    Returns
    -------
    Figure
        Red: intersecting faces the reference does not have (in the repaired poses: new ones);
        orange: intersecting faces the reference has too; purple: distorted faces.
    """
    panels = [(name, V, faces) for name, (V, faces) in poses.items()]
    over = [np.zeros(len(F), dtype=bool)] + list(distorted or [np.zeros(len(F), dtype=bool)] * (len(panels) - 1))
    limits = view_limits(*(V for _, V, _ in panels), R=R)
    fig = Figure(figsize=(5 * len(panels), panel_height(limits)), dpi=DPI)
    for i, ((name, V, faces), bad) in enumerate(zip(panels, over)):
        ax = fig.add_subplot(1, len(panels), i + 1)
        draw_mesh(ax, V, F, R, highlight=[(bad, DISTORTED), (faces & reference_faces, SECONDARY),
                                          (faces & ~reference_faces, HIGHLIGHT)], scale=limits)
        label = "not in the reference" if i == 0 else "new"
        extra = f", {bad.sum()} distorted" if bad.any() else ""
        ax.set_title(f"{name}: {faces.sum()} intersecting faces, {(faces & ~reference_faces).sum()} {label}{extra}",
                     fontsize=10)
    handles = [Patch(color=HIGHLIGHT, label="intersecting, not in the reference"),
               Patch(color=SECONDARY, label="intersecting in the reference too")]
    if distorted is not None:
        handles.append(Patch(color=DISTORTED, label="stretched or crushed beyond the distortion limit"))
    fig.legend(handles=handles, loc="lower center", ncol=len(handles), frameon=False, fontsize=9)
    fig.suptitle(title, fontsize=11)
    return fig


def deviation_map(X, F, R, deviation, replaced, title=""):
    """Heat map of the deviation from the target on the repaired pose, with a colour bar (S0 Fig. 7 style).

    Parameters
    ----------
    X : (n, 3) float
        Repaired positions.
    deviation : (n,) float
        ``|repaired - target| / d`` per vertex.
    replaced : (n,) uint8
        Flags per vertex (:mod:`posefix.verify.flags`); the right panel shows the vertices the fallback
        and the pushes moved (:data:`FLAG_COLORS`).
    """
    fig = Figure(figsize=(10, panel_height(view_limits(X, R=R))), dpi=DPI)
    ax = fig.add_subplot(1, 2, 1)
    colors, norm = heat_colors(face_values(deviation, F), colormaps[HEAT_MAP], heat_limit(deviation))
    draw_mesh(ax, X, F, R, colors=colors)
    ax.set_title(f"deviation from the target (max {deviation.max():.2g} d)", fontsize=10)
    bar = fig.colorbar(ScalarMappable(norm=norm, cmap=colormaps[HEAT_MAP]), ax=ax, shrink=0.8, extend="max")
    bar.set_label("|repaired - target| / bbox diagonal")
    ax = fig.add_subplot(1, 2, 2)
    colors = np.tile([0.78, 0.78, 0.80], (len(F), 1))
    handles = []
    for flag in FLAGS:
        faces = (replaced[F] & flag.bit).any(axis=1)
        if flag.bit in FLAG_COLORS and faces.any():
            colors[faces] = to_rgb(FLAG_COLORS[flag.bit])
            handles.append(Patch(color=FLAG_COLORS[flag.bit],
                                 label=f"{flag.label} ({np.count_nonzero(replaced & flag.bit)} vertices)"))
    draw_mesh(ax, X, F, R, colors=colors)
    ax.set_title("fallback regions", fontsize=10)
    ax.legend(handles=handles or [Patch(color=(0.78, 0.78, 0.80), label="no fallback")], loc="upper center",
              fontsize=8, frameon=False, bbox_to_anchor=(0.5, 0.0), ncol=2)
    fig.suptitle(title, fontsize=11)
    return fig


def classification(V_ref, F, R, mask, frame_counts, repaired, repaired_new, title=""):
    """Intersecting faces per key frame (before) and after the repair, and ``V_C`` on the reference.

    Parameters
    ----------
    mask : (n,) bool
        ``V_C``: vertices whose neighbourhood is free of intersections in every key frame.
    frame_counts : (K,) int
        Intersecting faces per key frame (0 the reference, K-1 the target).
    repaired, repaired_new : int
        Intersecting and new intersecting faces of the repaired pose.
    """
    fig = Figure(figsize=(10, 4.2), dpi=DPI)
    ax = fig.add_subplot(1, 2, 1)
    t = np.linspace(0, 1, len(frame_counts))
    ax.bar(t, frame_counts, width=0.8 / max(len(t) - 1, 1), color="tab:blue", label="key frames (before)")
    ax.axhline(repaired, color="tab:green", lw=2, label=f"repaired: {repaired}")
    ax.axhline(repaired_new, color="tab:red", lw=2, ls="--", label=f"repaired, new: {repaired_new}")
    ax.set_xlabel("key frame time t (0 reference, 1 target)")
    ax.set_ylabel("intersecting faces")
    ax.legend(fontsize=8)
    ax = fig.add_subplot(1, 2, 2)
    colors = np.where(mask[F].all(axis=1)[:, None], [CONSTRAINED], [FREE])
    draw_mesh(ax, V_ref, F, R, colors=colors)
    ax.set_title(f"V_C on the reference: {mask.sum()} of {len(mask)} vertices", fontsize=10)
    ax.legend(handles=[Patch(color=CONSTRAINED, label="V_C (constrained)"),
                       Patch(color=FREE, label="free (integrated through the field)")],
              loc="upper center", fontsize=8, frameon=False, bbox_to_anchor=(0.5, 0.0), ncol=2)
    fig.suptitle(title, fontsize=11)
    return fig


def fit_history(history, d, eps_rel, title=""):
    """Greedy fit per iteration: max and rms error, condition estimate, seconds (S0 Table 1, Fig. 5).

    Parameters
    ----------
    history : dict of (I,) arrays
        ``centers``, ``max_error``, ``rms_error``, ``condition``, ``seconds_evaluate``,
        ``seconds_select``, ``seconds_update`` (fit.h5 ``history/``).
    d : float
        Bounding-box diagonal.
    eps_rel : float
        Target max error / d.
    """
    fig = Figure(figsize=(12, 3.8), dpi=DPI)
    c = history["centers"]
    ax = fig.add_subplot(1, 3, 1)
    ax.semilogy(c, history["max_error"] / d, "o-", ms=3, label="max")
    ax.semilogy(c, history["rms_error"] / d, "s-", ms=3, label="rms")
    ax.axhline(eps_rel, color="k", ls=":", label=f"eps = {eps_rel:g}")
    ax.set_xlabel("centres")
    ax.set_ylabel("residual / bbox diagonal")
    ax.legend(fontsize=8)
    ax = fig.add_subplot(1, 3, 2)
    ax.semilogy(c, history["condition"], "o-", ms=3, color="tab:purple")
    ax.set_xlabel("centres")
    ax.set_ylabel("condition estimate kappa_1")
    ax = fig.add_subplot(1, 3, 3)
    bottom = np.zeros(len(c))
    width = 0.8 * (np.median(np.diff(c)) if len(c) > 1 else 1.0)
    for key, label in (("seconds_evaluate", "evaluate"), ("seconds_select", "select"), ("seconds_update", "update")):
        ax.bar(c, history[key], width=width, bottom=bottom, label=label)
        bottom = bottom + history[key]
    ax.set_xlabel("centres")
    ax.set_ylabel("seconds per iteration")
    ax.legend(fontsize=8)
    fig.suptitle(title, fontsize=11)
    fig.tight_layout()
    return fig


def timings(seconds, title=""):
    """Wall seconds per stage (Snakemake ``benchmark:`` files) as horizontal bars; ``seconds``: stage -> float or None."""
    stages = [s for s, v in seconds.items() if v is not None]
    values = [seconds[s] for s in stages]
    fig = Figure(figsize=(6, 0.45 * len(stages) + 1.2), dpi=DPI)
    ax = fig.add_subplot(1, 1, 1)
    ax.barh(stages, values, color="tab:blue")
    for y, v in enumerate(values):
        ax.text(v, y, f" {v:.2f}", va="center", fontsize=8)
    ax.invert_yaxis()
    ax.set_xlabel("wall seconds (incl. interpreter start)")
    ax.set_xlim(0, 1.15 * max(values + [1e-3]))
    ax.set_title(f"{title}: {sum(values):.1f} s in all", fontsize=10)
    fig.tight_layout()
    return fig


def downstream_history(runs, title=""):
    """Energy per Gauss–Newton iteration of the downstream check, one panel per alpha.

    Parameters
    ----------
    runs : list of dict
        One per run: ``alpha``, ``k_bend`` (floats), ``example`` ("original", "repaired" or a
        other repair's name, drawn dotted), ``errors`` (iterations + 1,) float, ``converged`` (bool),
        ``reason`` (str).
    """
    alphas = sorted({r["alpha"] for r in runs})
    k_bends = sorted({r["k_bend"] for r in runs})
    colors = {k: f"C{i}" for i, k in enumerate(k_bends)}
    repairs = sorted({r["example"] for r in runs} - set(EXAMPLE_STYLES))
    styles = "solid: repaired, dashed: original" + (f", dotted: {', '.join(repairs)}" if repairs else "")
    fig = Figure(figsize=(5 * len(alphas) + 1, 4.2), dpi=DPI)
    for i, alpha in enumerate(alphas):
        ax = fig.add_subplot(1, len(alphas), i + 1)
        for r in (r for r in runs if r["alpha"] == alpha):
            errors = np.maximum(r["errors"], 1e-30)
            style = EXAMPLE_STYLES.get(r["example"], ":")
            ax.semilogy(np.arange(len(errors)), errors, style, color=colors[r["k_bend"]],
                        label=f"{r['example']}, k_b {r['k_bend']:g}: {len(errors) - 1} it., "
                              f"{'converged' if r['converged'] else r['reason']}")
            ax.plot(len(errors) - 1, errors[-1], "o" if r["converged"] else "x", color=colors[r["k_bend"]])
        ax.set_xlabel("Gauss-Newton iteration")
        ax.set_ylabel("energy (sum of squared residuals)")
        ax.set_title(f"alpha = {alpha:g}", fontsize=9)
        ax.legend(fontsize=6.5)
    fig.suptitle(f"{title}\n({styles}; o converged, x not)", fontsize=10)
    fig.tight_layout()
    return fig


def _offsets(count):
    """x offsets and width of ``count`` bars side by side per pose, ((count,) float, float)."""
    width = 0.8 / count
    return (np.arange(count) - (count - 1) / 2) * width, width


def _intersection_panel(ax, x, entries, names):
    """Overview panel 1: intersecting faces of the target, new ones of the space-time repair and the others."""
    dx, width = _offsets(2 + len(names))
    ax.bar(x + dx[0], [e["intersecting_faces"]["target"] for e in entries], width, label="target")
    new = np.array([e["intersecting_faces"]["repaired_new"] for e in entries])
    inside = np.array([e["intersecting_faces"].get("repaired_new_in_fallback", 0) for e in entries])
    s0 = SPACETIME if names else "repaired"
    ax.bar(x + dx[1], new - inside, width, color="tab:red", label=f"{s0}: new")
    ax.bar(x + dx[1], inside, width, bottom=new - inside, color="tab:pink", label=f"{s0}: new, in pass-through")
    for j, name in enumerate(names):
        ax.bar(x + dx[2 + j], [e["repairs"][name]["intersecting_faces"]["repaired_new"] for e in entries], width,
               color=REPAIR_COLORS[j], label=f"{name}: new")
    ax.set_ylabel("intersecting faces")
    ax.legend(fontsize=8)


def _deviation_panel(ax, x, entries, names, bar):
    """Overview panel 2: deviations from the target, space-time filled markers, each other repair hollow beside it."""
    sources = [("space-time " if names else "", 0.0, "full", [e["deviation"] for e in entries])]
    sources += [(f"{name} ", 0.15 * (j + 1), "none", [e["repairs"][name]["deviation"] for e in entries])
                for j, name in enumerate(names)]
    for prefix, shift, fill, deviations in sources:
        for j, (key, marker, label) in enumerate(DEVIATION_MARKERS):
            ax.plot(x + shift, [d[key] for d in deviations], marker, color=f"C{j}", fillstyle=fill,
                    label=prefix + label)
    ax.axhline(bar, color="k", ls=":", label=f"bar {bar:g}")
    ax.set_yscale("symlog", linthresh=1e-5)
    ax.set_ylim(bottom=0)
    ax.set_ylabel("deviation / bbox diagonal (linear below 1e-5)")
    ax.legend(fontsize=8, ncol=1 + bool(names))


def _seconds_panel(ax, x, entries, names):
    """Overview panel 4: wall seconds per stage, and beside them each other repair's stage (hatched)."""
    dx, width = _offsets(1 + len(names))
    bottom = np.zeros(len(entries))
    for stage in entries[0]["seconds_stages"]:
        values = np.array([e["seconds_stages"].get(stage) or 0.0 for e in entries])
        ax.bar(x + dx[0], values, width, bottom=bottom, label=stage)
        bottom += values
    for j, name in enumerate(names):
        ax.bar(x + dx[1 + j], [e["repairs"][name]["seconds"] for e in entries], width, color=REPAIR_COLORS[j],
               hatch="//", label=f"{name} repair")
    ax.set_ylabel("wall seconds per stage")
    ax.legend(fontsize=7, ncol=2)


def _downstream_panels(fig, x, entries, names):
    """Overview panels 5 and 6: Gauss–Newton convergence (original, repaired and the other repairs ``names``)
    and iterations, original vs repaired."""
    counts, s0 = [downstream_counts(e) for e in entries], SPACETIME if names else "repaired pose"
    series = [([c["converged_original"] for c in counts], "original target", "tab:gray"),
              ([c["converged_repaired"] for c in counts], s0, "tab:green")]
    series += [([converged_runs(e["repairs"][name]["downstream"], name) for e in entries], name, REPAIR_COLORS[j])
               for j, name in enumerate(names)]
    ax = fig.add_subplot(3, 2, 5)
    dx, width = _offsets(len(series))
    for offset, (values, label, color) in zip(dx, series):
        ax.bar(x + offset, values, width, color=color, label=label)
    ax.axhline(counts[0]["runs"], color="k", ls=":", label="runs per example")
    ax.set_ylabel("converged Gauss-Newton runs")
    ax.legend(fontsize=8)
    ax = fig.add_subplot(3, 2, 6)
    ax.bar(x - 0.2, [c["paired_original"] for c in counts], 0.4, color="tab:gray", label="original target")
    ax.bar(x + 0.2, [c["paired_repaired"] for c in counts], 0.4, color="tab:green", label=s0)
    for xi, c in zip(x, counts):
        ax.annotate(str(c["paired"]), (xi, max(c["paired_original"], c["paired_repaired"])), ha="center",
                    va="bottom", fontsize=7)
    ax.set_ylabel("iterations where both converged (n runs on top)")
    ax.legend(fontsize=8)


def library_overview(entries, bar=DEVIATION_BAR, title=""):
    """All poses of a library at a glance: intersections, deviation, centres, seconds, and the
    downstream Gauss–Newton check (converged runs, iterations) when the entries have it; the
    other repairs (``summary.json``'s ``repairs``) beside space-time's.

    Parameters
    ----------
    entries : list of dict
        ``summary.json`` entries (one per pose).
    bar : float
        Acceptance bar of the constrained-region max deviation / d (drawn as a line).
    """
    poses = [e["pose"] for e in entries]
    x = np.arange(len(poses))
    names = repair_names(entries)
    rows = 3 if all("downstream" in e for e in entries) else 2
    fig = Figure(figsize=(max(10, (0.9 + 0.3 * len(names)) * len(poses) + 4), 3.75 * rows), dpi=DPI)
    _intersection_panel(fig.add_subplot(rows, 2, 1), x, entries, names)
    _deviation_panel(fig.add_subplot(rows, 2, 2), x, entries, names, bar)
    ax = fig.add_subplot(rows, 2, 3)
    ax.bar(x - 0.2, [e["fit"]["centers"] for e in entries], 0.4, color="tab:purple", label="RBF centres")
    ax.bar(x + 0.2, [e["fallback_vertices"] for e in entries], 0.4, color="tab:orange", label="fallback vertices")
    ax.set_yscale("symlog", linthresh=10)
    ax.set_ylim(bottom=0)
    ax.set_ylabel("count")
    ax.legend(fontsize=8)
    _seconds_panel(fig.add_subplot(rows, 2, 4), x, entries, names)
    if rows == 3:
        checked = [n for n in names if all("downstream" in e["repairs"][n] for e in entries)]
        _downstream_panels(fig, x, entries, checked)
    for ax in fig.axes:
        ax.set_xticks(x, poses, rotation=45, ha="right", fontsize=8)
    fig.suptitle(title, fontsize=12)
    fig.tight_layout()
    return fig
