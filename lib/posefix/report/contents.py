"""What the report of a library holds: the figures of each pose and the stages whose times it shows.

Shared by the workflow (``rules/report.smk`` declares the figures as outputs, with captions in
``rules/captions/<figure>.rst``) and stage ``render``, which draws them. No plotting here, so the
workflow can import it cheaply.
"""

POSE_FIGURES = {
    "renders": "target vs repaired",
    "deviation": "deviation heat map",
    "classification": "intersections per key frame, V_C",
    "fit": "fit history",
    "timings": "stage timings",
}
"""Figures of stage ``render`` per pose: file name (``<name>.png``) -> label in the Snakemake report."""

TIMED_STAGES = ("keyframes", "classify", "constraints", "fit", "integrate", "verify")
"""Stages whose wall seconds (Snakemake benchmark files) the ``timings`` figure shows."""

VIEWER_FILES = {"template": "page/viewer.html", "script": "page/viewer.js",
                "three": "vendor/three/three.module.min.js", "controls": "vendor/three/OrbitControls.js"}
"""Files of the 3D viewer page (``viewer.html``), relative to this package's folder: its template and script, and
three.js vendored for it (``vendor/three/README.md``). Stage ``viewer`` inlines them; the workflow lists them as
the rule's inputs, so that a changed page rebuilds it."""
