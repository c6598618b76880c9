"""Library-level tables of the report: one row per pose of ``summary.json``, with a status per pose."""

import html

from posefix.mesh.distortion import DISTORTED_SHARE, SEVERE
from posefix.report.contents import SPACETIME, TIMED_STAGES

DEVIATION_BAR = 1e-3
"""Constrained-region max deviation / d above which a pose is flagged."""
STATUS_COLORS = {"ok": "#d8f0d8", "fallback": "#fff2c6", "check": "#f8d0d0"}


def pose_status(entry):
    """Status of one pose from its summary entry: ``(kind, reason)`` with kind ``ok``, ``fallback`` or ``check``.

    The summary stage stores it in the entry (``status``, :func:`entry_status` reads it); ``check``: new
    intersecting faces outside the pass-through fallback, a constrained-region max deviation above
    :data:`DEVIATION_BAR`, a contact finish reverted to the path lines or not converged, a face stretched or crushed
    beyond :data:`posefix.mesh.distortion.SEVERE` or more than :data:`posefix.mesh.distortion.DISTORTED_SHARE` of the faces beyond the
    entry's distortion limit (against both the target and the reference); ``fallback``: regions copied from the
    target or untangled (the pose is clean but not all of it came from the integration); ``ok`` otherwise. The
    contact finish's only copy from the target is where the target undoes the reference's own intersections (the
    cat's paws, through each other at rest): the target is the right shape there, and the pose is ``ok`` with that
    reason.
    """
    faces = entry["intersecting_faces"]
    outside = faces["repaired_new"] - faces.get("repaired_new_in_fallback", 0)
    reasons = []
    if outside > 0:
        reasons.append(f"{outside} new intersecting faces")
    if entry["deviation"]["constrained_max"] > DEVIATION_BAR:
        reasons.append(f"V_C max deviation {entry['deviation']['constrained_max']:.2g} > {DEVIATION_BAR:g}")
    finish = entry.get("finish", {})
    if finish.get("reverted"):
        reasons.append("the contact finish fell back to the path lines (a step it could not bound)")
    elif finish and not finish.get("converged", True):
        reasons.append("the contact finish did not converge")
    reasons += _distortion_reasons(entry)
    if reasons:
        return "check", "; ".join(reasons)
    fallback = entry.get("fallback", {})
    if entry["fallback_vertices"] > 0 and finish and not fallback.get("pass_through", 0):
        return "ok", f"{entry['fallback_vertices']} vertices take the target, which undoes the reference's own " \
                     "intersections there"
    if entry["fallback_vertices"] > 0:
        parts = [f"{fallback.get(k, 0)} {k.replace('_', '-')}" for k in ("pass_through", "new_intersection")
                 if fallback.get(k, 0)]
        return "fallback", f"{entry['fallback_vertices']} vertices ({', '.join(parts) or 'untangled'})"
    return "ok", ""


def _distortion_reasons(entry):
    """The distortion part of :func:`pose_status`'s reasons, list of str."""
    distortion = entry.get("distortion", {})
    reasons = []
    if distortion.get("faces_severe", 0) > 0:
        reasons.append(f"{distortion['faces_severe']} faces stretched or crushed beyond {SEVERE:g}x")
    over = distortion.get("faces_over", 0)
    if over > DISTORTED_SHARE * entry["faces"]:
        reasons.append(f"{over} faces ({100 * over / entry['faces']:.2g}%) stretched or crushed beyond "
                       f"{distortion['limit']:g}x")
    return reasons


def entry_status(entry):
    """``(kind, reason)`` of a summary entry as the summary stage stored it (:func:`pose_status`)."""
    return entry["status"]["kind"], entry["status"]["reason"]


def downstream_counts(entry):
    """Gauss–Newton runs of one pose (``summary.json``'s ``downstream``) tallied, dict.

    ``runs`` per example, ``converged_original`` / ``converged_repaired`` counts,
    ``iterations_original`` / ``iterations_repaired`` summed over all runs, and ``paired`` with
    the iterations summed over the settings where both converged (the fair comparison of speed).
    """
    out = {"runs": 0, "converged_original": 0, "converged_repaired": 0, "iterations_original": 0,
           "iterations_repaired": 0, "paired": 0, "paired_original": 0, "paired_repaired": 0}
    for per in entry["downstream"]["alphas"].values():
        o, r = per["original"], per["repaired"]
        out["runs"] += len(o["iterations"])
        for name, runs in (("original", o), ("repaired", r)):
            out[f"converged_{name}"] += sum(runs["converged"])
            out[f"iterations_{name}"] += sum(runs["iterations"])
        for io, co, ir, cr in zip(o["iterations"], o["converged"], r["iterations"], r["converged"]):
            if co and cr:
                out["paired"] += 1
                out["paired_original"] += io
                out["paired_repaired"] += ir
    return out


def downstream_markdown(entries):
    """Markdown table of :func:`downstream_counts` per pose and in total, list of str lines."""
    lines = ["| pose | runs | converged original | converged repaired | iterations original / repaired (all runs) "
             "| both converged | their iterations original / repaired | fewer |",
             "|---|---:|---:|---:|---|---:|---|---:|"]
    total = {}
    for e in entries:
        c = downstream_counts(e)
        total = {k: total.get(k, 0) + v for k, v in c.items()}
        lines.append(_downstream_row(e["pose"], c))
    if len(entries) > 1:
        lines.append(_downstream_row("**all**", total))
    return lines


def downstream_grid_markdown(entries):
    """Markdown table of the downstream check per setting (alpha, k_b) over all poses, list of str lines:
    converged runs original / repaired and the iterations of the settings where both converged."""
    cells = {}
    for e in entries:
        d = e["downstream"]
        for alpha, per in d["alphas"].items():
            o, r = per["original"], per["repaired"]
            for j, k in enumerate(d["k_bend"]):
                c = cells.setdefault((float(alpha), k), [0, 0, 0, 0, 0, 0])
                both = o["converged"][j] and r["converged"][j]
                for i, v in enumerate((1, o["converged"][j], r["converged"][j], both,
                                       both * o["iterations"][j], both * r["iterations"][j])):
                    c[i] += int(v)
    lines = ["| alpha | k_b | poses | converged original | converged repaired | both | their iterations "
             "original / repaired | fewer |", "|---:|---:|---:|---:|---:|---:|---|---:|"]
    for (alpha, k), (n, co, cr, both, io, ir) in sorted(cells.items()):
        fewer = f"{1 - ir / io:.0%}" if io else "-"
        lines.append(f"| {alpha:g} | {k:g} | {n} | {co} | {cr} | {both} | {io} / {ir} | {fewer} |")
    return lines


def _downstream_row(name, c):
    fewer = (f"{1 - c['paired_repaired'] / c['paired_original']:+.0%}".replace("+", "") if c["paired_original"]
             else "-")
    return (f"| {name} | {c['runs']} | {c['converged_original']} | {c['converged_repaired']} | "
            f"{c['iterations_original']} / {c['iterations_repaired']} | {c['paired']} | "
            f"{c['paired_original']} / {c['paired_repaired']} | {fewer} |")


def repair_names(entries):
    """The other repairs every entry has (``summary.json``'s ``repairs``), in their order, list of str."""
    first = entries[0].get("repairs", {}) if entries else {}
    return [name for name in first if all(name in e.get("repairs", {}) for e in entries)]


def repair_seconds(entry):
    """Wall seconds of the space-time repair of a pose: its stages keyframes to verify (:data:`TIMED_STAGES`,
    ``seconds_stages`` from the Snakemake benchmark files), float."""
    return sum(entry["seconds_stages"].get(stage) or 0.0 for stage in TIMED_STAGES)


def converged_runs(downstream, example):
    """Converged Gauss–Newton runs towards ``example`` in a summary's ``downstream``, int."""
    return sum(sum(per[example]["converged"]) for per in downstream["alphas"].values())


def compared_repairs(entry, names):
    """The space-time repair of a pose and the other repairs ``names``, side by side: ``{"space-time": ..., name: ...}``.

    Each value has ``new`` (new intersecting faces), ``constrained_mean``, ``constrained_max``,
    ``free_max`` (deviations / d), ``edge`` and ``distorted`` (worst edge-length ratio against the target,
    faces beyond the distortion limit; None where not measured), ``seconds`` (space-time: :func:`repair_seconds`; another repair: its own) and
    ``converged`` (converged Gauss–Newton runs towards it; None without the check).
    """
    out = {SPACETIME: _compared(entry, repair_seconds(entry), "repaired")}
    for name in names:
        out[name] = _compared(entry["repairs"][name], entry["repairs"][name]["seconds"], name)
    return out


def _compared(repair, seconds, example):
    """One value of :func:`compared_repairs` from an entry or another repair's entry (the same keys)."""
    dev, down, distortion = repair["deviation"], repair.get("downstream"), repair.get("distortion", {})
    return {"new": repair["intersecting_faces"]["repaired_new"], "constrained_mean": dev["constrained_mean"],
            "constrained_max": dev["constrained_max"], "free_max": dev["free_max"],
            "edge": distortion.get("edge_target"), "distorted": distortion.get("faces_over"), "seconds": seconds,
            "converged": None if down is None else converged_runs(down, example)}


COMPARISON = (("new faces", "new", "{}"), ("V_C dev. mean", "constrained_mean", "{:.2g}"),
              ("V_C dev. max", "constrained_max", "{:.2g}"), ("free dev. max", "free_max", "{:.2g}"),
              ("worst edge ratio", "edge", "{:.3g}"), ("distorted faces", "distorted", "{}"),
              ("seconds", "seconds", "{:.1f}"), ("GN converged", "converged", "{}"))
"""Columns of :func:`comparison_table`: label, key of :func:`compared_repairs`, format."""


def comparison_table(entries):
    """Space-time vs the other repairs per pose: ``(header, rows)``, lists of str, one cell ``space-time / <repair> ...``
    per :data:`COMPARISON` column (``GN converged`` only when every repair has the downstream check, the
    distortion columns only when every repair was measured);
    ``([], [])`` without repairs."""
    names = repair_names(entries)
    if not names:
        return [], []
    repairs = [compared_repairs(e, names) for e in entries]
    columns = [c for c in COMPARISON
               if all(r[c[1]] is not None for rs in repairs for r in rs.values())]
    header = ["pose"] + [f"{label} {' / '.join(['space-time', *names])}" for label, _, _ in columns]
    rows = [[e["pose"]] + [" / ".join(fmt.format(r[key]) for r in rs.values()) for _, key, fmt in columns]
            for e, rs in zip(entries, repairs)]
    return header, rows


def comparison_note(header):
    """What the columns of a :func:`comparison_table` with ``header`` mean, str."""
    note = ("'new faces': intersecting in the repaired pose but not in the reference; deviations from the target "
            "relative to the bbox diagonal, over space-time's V_C and the rest; seconds: space-time's stages keyframes to verify "
            "(benchmark files), another repair's stage (without the skeleton, once per library)")
    if any(h.startswith("worst edge ratio") for h in header):
        note += ("; 'worst edge ratio': the largest edge-length ratio (or its inverse) against the target; "
                 "'distorted faces': faces whose edge-length or area ratio exceeds the distortion limit against both "
                 "the target and the reference")
    if header[-1].startswith("GN converged"):
        note += "; 'GN converged': Gauss-Newton runs towards the repaired pose that converged (downstream check)"
    return note + "."


def comparison_markdown(entries):
    """``summary.md``'s section comparing space-time with the other repairs, list of str lines (none without repairs)."""
    header, rows = comparison_table(entries)
    if not rows:
        return []
    return (["", "## Space-time vs the other repairs", "", "| " + " | ".join(header) + " |",
             "|---|" + "---:|" * (len(header) - 1)] + ["| " + " | ".join(row) + " |" for row in rows]
            + ["", comparison_note(header)])


def _comparison_html(entries):
    """The HTML section of :func:`comparison_table` (empty without repairs), str."""
    header, rows = comparison_table(entries)
    if not rows:
        return ""
    head = "".join(f"<th>{html.escape(h)}</th>" for h in header)
    body = "".join("<tr>" + "".join(f"<td>{html.escape(c)}</td>" for c in row) + "</tr>" for row in rows)
    return (f"<h3>Space-time vs the other repairs</h3><p>{html.escape(comparison_note(header))}</p>"
            f"<table><thead><tr>{head}</tr></thead><tbody>{body}</tbody></table>")


COLUMNS = (
    ("pose", lambda e: e["pose"]),
    ("status", None),
    ("target faces", lambda e: e["intersecting_faces"]["target"]),
    ("key frames max", lambda e: e["intersecting_faces"]["keyframes_max"]),
    ("repaired faces", lambda e: e["intersecting_faces"]["repaired"]),
    ("new (in pass-through)", lambda e: f"{e['intersecting_faces']['repaired_new']} "
                                        f"({e['intersecting_faces'].get('repaired_new_in_fallback', 0)})"),
    ("V_C", lambda e: e["constraint_vertices"]),
    ("V_C dev. mean / max", lambda e: f"{e['deviation']['constrained_mean']:.2g} / {e['deviation']['constrained_max']:.2g}"),
    ("free dev. mean / max", lambda e: f"{e['deviation']['free_mean']:.2g} / {e['deviation']['free_max']:.2g}"),
    ("centres", lambda e: e["fit"]["centers"]),
    ("fit max error / d", lambda e: f"{e['fit']['max_error_rel']:.2g}"),
    ("kappa", lambda e: f"{e['fit']['max_condition']:.2g}"),
    ("fallback vertices", lambda e: e["fallback_vertices"]),
    ("worst edge / area ratio (distorted faces)", lambda e: "{edge_target:.3g} / {area_target:.3g} ({faces_over})".format(
        **e["distortion"]) if "distortion" in e else "-"),
    ("fit s", lambda e: f"{e['fit']['seconds']:.1f}"),
    ("integrate s", lambda e: f"{e['integrate']['seconds']:.2f}"),
    ("GN converged original / repaired", lambda e: "{converged_original} / {converged_repaired} of {runs}".format(
        **downstream_counts(e)) if "downstream" in e else "-"),
    ("total s", lambda e: f"{e['seconds_total']:.1f}"),
)


def _failed_html(failed):
    """The list of the poses that did not finish (``{"pose", "error"}`` each), HTML; empty when none."""
    if not failed:
        return ""
    items = "".join(f"<li><b>{html.escape(f['pose'])}</b>: {html.escape(f['error'])}</li>" for f in failed)
    return (f'<p style="background:{STATUS_COLORS["check"]}">{len(failed)} pose(s) did not finish (the table has '
            f"the others):</p><ul>{items}</ul>")


def summary_html(library, entries, failed=()):
    """A self-contained HTML page with the library's table, rows coloured by their status (:func:`entry_status`),
    str; ``failed``:
    ``{"pose", "error"}`` of the poses that did not finish, listed above the table."""
    counts = {}
    rows = []
    for entry in entries:
        kind, reason = entry_status(entry)
        counts[kind] = counts.get(kind, 0) + 1
        cells = [html.escape(f"{kind}: {reason}" if reason else kind) if get is None else html.escape(str(get(entry)))
                 for _, get in COLUMNS]
        rows.append(f'<tr style="background:{STATUS_COLORS[kind]}">' + "".join(f"<td>{c}</td>" for c in cells) + "</tr>")
    head = "".join(f"<th>{html.escape(name)}</th>" for name, _ in COLUMNS)
    tally = ", ".join(f"{counts.get(k, 0)} {k}" for k in STATUS_COLORS)
    return (f"<!DOCTYPE html>\n<html><head><meta charset='utf-8'><title>posefix: {html.escape(library)}</title>"
            "<style>body{font-family:sans-serif;font-size:13px}table{border-collapse:collapse}"
            "td,th{border:1px solid #999;padding:3px 6px;text-align:right}th{background:#eee}</style></head><body>"
            f"<h2>posefix summary: {html.escape(library)}</h2>{_failed_html(failed)}"
            "<p><a href='viewer.html'>3D viewer</a> (viewer.html beside this page): every pose's target, repairs and "
            "reference, intersecting faces, deviation heat map.</p>"
            f"<p>{len(entries)} poses: {tally}. ok: clean and within the deviation bar (the contact "
            "finish taking the target where it undoes the reference's own intersections included); fallback: clean, "
            "with regions copied from the target or untangled; check: new intersecting faces outside the pass-through "
            f"fallback, a V_C max deviation above {DEVIATION_BAR:g} of the bbox diagonal, a contact finish that fell "
            f"back or did not converge, a face stretched or crushed beyond {SEVERE:g}x or more than "
            f"{100 * DISTORTED_SHARE:g}% of the faces beyond the distortion limit, against both the target and the "
            "reference (ratios against the target). Deviations are relative to the reference's bbox diagonal.</p>"
            f"<table><thead><tr>{head}</tr></thead><tbody>{''.join(rows)}</tbody></table>"
            f"{_comparison_html(entries)}</body></html>\n")
