"""The summary of a library: one entry per pose from its stages' metrics, as JSON and as Markdown.

The entry schema is in ``docs/artifacts.md`` (``summary.json``). Stage ``summary`` reads the
artifacts' metrics and Snakemake's benchmark files and calls :func:`pose_entry` per pose.
"""

import numpy as np

from posefix.downstream.check import EXAMPLES
from posefix.downstream.gauss_newton import STOP_REASONS
from posefix.report.tables import comparison_markdown, downstream_markdown, pose_status

DEVIATIONS = ("constrained_max", "constrained_mean", "constrained_p95", "free_max", "free_mean", "free_p95")
"""Deviation summaries of a pose (relative to the bbox diagonal)."""
SUMMARY_STAGES = ("keyframes", "classify", "constraints", "fit", "integrate", "verify", "export", "downstream")
"""Stages whose wall seconds a summary entry adds up (``seconds_stages``)."""


def pose_entry(pose, metrics, downstream, seconds, repairs=None, distortion=None):
    """The summary entry of one pose.

    Parameters
    ----------
    pose : str
    metrics : dict of str -> dict
        The ``metrics`` of the pose's artifacts by stage (``keyframes``, ``fit`` (with the constraints' counts:
        ``constraints.h5`` is an intermediate), ``integrate``, ``verify``).
    downstream : dict of str -> ndarray
        Datasets of ``downstream.h5`` (:func:`downstream_entry`).
    seconds : dict of str -> float or None
        Wall seconds per stage of :data:`SUMMARY_STAGES` (None where unknown).
    repairs : dict of str -> dict, optional
        :func:`repair_entry` per other repair of the pose (key ``repairs``; none: no key).
    distortion : dict, optional
        :func:`posefix.mesh.distortion.distortion_summary` of the repaired pose against the target and the
        reference (key ``distortion``; none: no key).

    Returns
    -------
    dict
        With its ``status`` (:func:`posefix.report.tables.pose_status`), which every page and the terminal read.
    """
    kf, fi, it = (metrics[s] for s in ("keyframes", "fit", "integrate"))
    entry = {
        "pose": pose, "vertices": int(kf["vertices"]), "faces": int(kf["faces"]), "keyframes": int(kf["keyframes"]),
        "constraint_vertices": int(fi["constraint_vertices"]), "constraints": int(fi["constraints"]),
        "fit": {"centers": int(fi["centers"]), "iterations": int(fi["iterations"]), "stop_reason": str(fi["stop_reason"]),
                "max_error_rel": float(fi["max_error_rel"]), "rms_error_rel": float(fi["rms_error_rel"]),
                "max_condition": float(fi["max_condition"]), "seconds": float(fi["seconds"])},
        "integrate": {"backend": str(it["backend"]), "device": str(it["device"]), "seconds": float(it["seconds"]),
                      "steps_mean": float(it["steps_mean"]), "steps_max": int(it["steps_max"])},
        "downstream": downstream_entry(downstream),
        **({"repairs": repairs} if repairs else {}),
        "seconds_stages": seconds, "seconds_total": sum(v for v in seconds.values() if v is not None)}
    return entry | verified_entry(metrics["verify"], entry["faces"], distortion)


def verified_entry(verify, faces, distortion=None):
    """The part of a pose's summary entry that its repair decides, with the pose's ``status``
    (:func:`posefix.report.tables.pose_status`): intersecting faces, deviations, the finish, the fallback and
    ``distortion`` (as :func:`pose_entry`'s), from verify's ``metrics`` (dict) of a pose of ``faces`` faces."""
    entry = _finish_entry(verify) | {
        "intersecting_faces": {
            "reference": int(verify["intersecting_faces_reference"]),
            "target": int(verify["intersecting_faces_target"]),
            "repaired": int(verify["intersecting_faces_repaired"]), "repaired_new": int(verify["repaired_new"]),
            "repaired_new_in_fallback": int(verify["repaired_new_in_fallback"]),
            "keyframes_max": int(verify["intersecting_faces_keyframes_max"])},
        "deviation": {k: float(verify[f"deviation_{k}"]) for k in DEVIATIONS},
        "integrated_deviation": {k: float(verify[f"integrated_deviation_{k}"]) for k in DEVIATIONS},
        "fallback_vertices": int(verify["fallback_vertices"]),
        "fallback": {"pass_through": int(verify["fallback_pass_through"]),
                     "new_intersection": int(verify["fallback_new_intersection"]),
                     "reproduced": int(verify["reproduced_vertices"]), "pushed": int(verify["pushed_vertices"])},
        **({"distortion": distortion} if distortion else {})}
    return entry | {"status": dict(zip(("kind", "reason"), pose_status(entry | {"faces": faces})))}


def _finish_entry(verify):
    """``{"finish": {"converged", "reverted", "start"}}`` of the contact finish from verify's metrics; ``{}`` for
    the snap finish."""
    if "contact_converged" not in verify:
        return {}
    return {"finish": {"converged": bool(verify["contact_converged"]), "reverted": bool(verify["contact_reverted"]),
                       "start": str(verify.get("contact_start", "integrated"))}}


def repair_entry(name, metrics, deviation, downstream, distortion=None):
    """The summary of one other repair of a pose (``repairs.<name>`` of its entry).

    Parameters
    ----------
    name : str
        The other repair (``medial``).
    metrics : dict
        The ``metrics`` of its artifact (``<pose>/<name>.h5``).
    deviation : dict
        Deviation summary of its repaired pose from the target over ``V_C`` and the rest
        (:func:`posefix.verify.deviation.deviation`, the same as space-time's).
    downstream : dict of str -> ndarray
        Datasets of ``downstream.h5``; the entry gets a ``downstream`` like space-time's (:func:`downstream_entry`)
        when the check ran towards the other repair.
    distortion : dict, optional
        As :func:`pose_entry`'s, of the other repair's repaired pose.

    Returns
    -------
    dict
    """
    entry = {"intersecting_faces": {"repaired": int(metrics["intersecting_faces_repaired"]),
                                    "repaired_new": int(metrics["intersecting_faces_repaired_new"])},
             "deviation": {k: float(deviation[k]) for k in DEVIATIONS},
             "iterations": int(metrics["iterations"]), "seconds": float(metrics["seconds"])}
    if distortion:
        entry["distortion"] = distortion
    if name in example_names(downstream):
        entry["downstream"] = downstream_entry(downstream, (name,))
    return entry


DOWNSTREAM_DATASETS = ("alpha", "k_bend", "example", "examples", "iterations", "converged", "reason", "final_error",
                       "seconds")
"""The datasets of ``downstream.h5`` that :func:`downstream_entry` reads."""


def example_names(d):
    """Names of the example codes of ``downstream.h5`` (its ``examples``, as read back), list of str."""
    return [n.decode() if isinstance(n, bytes) else str(n) for n in d["examples"]]


def downstream_entry(d, examples=EXAMPLES):
    """``downstream`` of a summary entry: per alpha and example, lists over k_b.

    Parameters
    ----------
    d : dict of str -> ndarray
        :data:`DOWNSTREAM_DATASETS` of ``downstream.h5``.
    examples : sequence of str
        The examples to list: space-time's (the original target and the repaired pose), or another repair's name.
        ``seconds`` sums their runs.
    """
    codes = {name: code for code, name in enumerate(example_names(d))}
    mine = np.isin(d["example"], [codes[name] for name in examples])
    entry = {"k_bend": sorted(set(d["k_bend"].tolist())), "alphas": {}, "seconds": float(d["seconds"][mine].sum())}
    for alpha in sorted(set(d["alpha"].tolist())):
        per = entry["alphas"][f"{alpha:g}"] = {}
        for name in examples:
            runs = list(np.flatnonzero((d["alpha"] == alpha) & (d["example"] == codes[name])))
            runs.sort(key=lambda i: d["k_bend"][i])
            per[name] = {"iterations": [int(d["iterations"][i]) for i in runs],
                         "converged": [bool(d["converged"][i]) for i in runs],
                         "reason": [STOP_REASONS[d["reason"][i]] for i in runs],
                         "final_error": [float(d["final_error"][i]) for i in runs]}
    return entry


def summary_markdown(library, entries, failed=()):
    """``summary.md`` of a library: one row per pose and the downstream table, str; ``failed``: ``{"pose",
    "error"}`` of the poses that did not finish, listed at the top."""
    head = ("| pose | faces | intersecting: reference / target / keyframes max / repaired | new (in fallback) | "
            "V_C | centres | fit stop | max error / d | max kappa | fit s | integrate s | steps | "
            "deviation V_C mean / max | (integrated) | free mean / max | fallback vertices | total s |")
    lines = [f"# posefix summary: {library}", ""] + failed_markdown(failed) + [head,
             "|---|---:|---|---|---:|---:|---|---:|---:|---:|---:|---:|---|---|---|---:|---:|"]
    lines += [_markdown_row(e) for e in entries]
    backends = sorted({f"{e['integrate']['backend']} ({e['integrate']['device']})" for e in entries})
    lines += ["", f"Integration: {', '.join(backends)}. Deviations are relative to the reference's bbox diagonal; "
              "'new' counts faces intersecting in the repaired pose but not in the reference, in brackets those "
              "inside regions copied from the target (pass-through fallback, S0 Fig. 9); '(integrated)' is the "
              "deviation of the integrated pose, before the fallback and the reproduction of V_C."]
    lines += ["", "## Downstream check: Gauss-Newton discrete shells (S0 §5)", "",
              *downstream_markdown(entries), "",
              "Example-driven deformation (Froehlich & Botsch 2011) from the reference towards the original target and "
              "towards the repaired pose, over the grid of alpha x k_b in config downstream; 'fewer': iteration "
              "reduction over the settings where both converged."]
    lines += comparison_markdown(entries)
    return "\n".join(lines) + "\n"


def failed_markdown(failed):
    """Lines of ``summary.md`` that list the poses that did not finish, ``failed``: ``{"pose", "error"}`` each."""
    if not failed:
        return []
    return [f"**{len(failed)} pose(s) did not finish** (the table has the others):", "",
            *(f"- {f['pose']}: {f['error']}" for f in failed), ""]


def _markdown_row(e):
    i, f, it, dv, di = e["intersecting_faces"], e["fit"], e["integrate"], e["deviation"], e["integrated_deviation"]
    return (f"| {e['pose']} | {e['faces']} | {i['reference']} / {i['target']} / {i['keyframes_max']} / {i['repaired']} | "
            f"{i['repaired_new']} ({i['repaired_new_in_fallback']}) | {e['constraint_vertices']} | {f['centers']} | "
            f"{f['stop_reason']} | {f['max_error_rel']:.2g} | {f['max_condition']:.2g} | {f['seconds']:.1f} | "
            f"{it['seconds']:.2f} | {it['steps_mean']:.1f} | {dv['constrained_mean']:.2g} / {dv['constrained_max']:.2g} | "
            f"({di['constrained_mean']:.2g} / {di['constrained_max']:.2g}) | "
            f"{dv['free_mean']:.2g} / {dv['free_max']:.2g} | {e['fallback_vertices']} | {e['seconds_total']:.1f} |")
