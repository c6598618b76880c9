"""What the report of a library holds: the figures of each pose and the stages whose times it shows.

Shared by the workflow (``rules/report.smk`` declares the figures as outputs, with captions in
``rules/captions/<figure>.rst``) and stage ``render``, which draws them. No plotting here, so the
workflow can import it cheaply.
"""

REPAIRS = {"spacetime": "space-time", "medial": "medial", "volumetric": "volumetric", "contact": "contact"}
"""The repairs: identifier (its package ``posefix.<id>``, rules file ``rules/<id>.smk``, tests folder ``tests/<id>``, and
for the others than space-time its config section and ``repairs`` entry) -> its label in the report, the viewer and
the API (``tests/test_names.py`` checks them all)."""

SPACETIME = REPAIRS["spacetime"]
"""The label of the space-time repair, the one the others are compared with."""

COMPARED_REPAIRS = tuple(name for name in REPAIRS if name != "spacetime")
"""The repairs config ``repairs`` may name: stage ``repair_<name>`` writes ``results/<library>/<pose>/<name>.h5``."""

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
