"""Memory a stage needs for a mesh of a given size: the rules' ``resources.mem_mb`` and the refusal, before a run
starts, of a reference too large for the memory it may use.

Only the workflow reads this module (``rules/common.smk``), no stage: a new measurement changes what the rules ask
Snakemake for, and reruns nothing.
"""

PEAK_MB = {
    "validate_reference": (115, 1.4), "validate": (113, 1.5), "keyframes": (118, 2.5), "classify": (104, 13.1),
    "constraints": (100, 3.5), "integrate": (188, 0.3), "verify": (63, 21.6), "export": (109, 2.0),
    "downstream": (310, 24.6), "skeleton": (133, 6.0), "repair_medial": (112, 6.3), "tet_mesh": (175, 0.8),
    "repair_volumetric": (202, 22.3), "repair_contact": (64, 21.5), "export_repair": (115, 1.9), "render": (141, 7.7),
    "viewer": (115, 1.7),
}
"""Peak memory of each stage (Snakemake's max_rss) as MB at rest plus MB per 1000 reference vertices: the line
through lion-01 (5.0k vertices) and kids-0001's 0001.isometry.1 (59.7k) with every repair, ``snakemake --cores 2``
(reports/bench/memory.md, ``benchmarks/memory.py``); the kids pose subdivided to 239k vertices stays within the
margin (at most 18 % above the line: keyframes) in the stages it ran, verify's 4.1 GB included. The skeleton's and
the volumetric repair's lines are the latest run's (f2b5d3f: up to 37 % above the run before); the downstream
check's is the line through its three sizes with its Cholesky on CHOLMOD (6429b20: 431, 1689 and 6089 MB); the
others that run's (the latest peaks at most 6 % above them). The 3D viewer's is the line through lion (123 MB: 9
poses with every repair, read one at a time) and a synthetic 92k-vertex pose with three other repairs (265 MB). The
fit's rule asks for its kernel cache's budget instead (config fit.memory_gb: the cache shrinks to what the job
gets)."""
OTHER_MB = (300, 10)
"""The same for a stage not in PEAK_MB (the summary's, the authoring stages)."""
MARGIN = 1.25
"""Headroom over the measured line."""
FLOOR_MB = 1000
"""Least memory a rule asks for (Snakemake's own default: a cluster job never gets less)."""


def stage_memory_mb(stage, vertices):
    """Memory a stage needs for a reference of ``vertices`` vertices (MB, int): the rule's ``resources.mem_mb``.

    Parameters
    ----------
    stage : str
        Rule name (``classify``, ``repair_volumetric``, ...).
    vertices : int
        Vertex count of the reference (all poses share it).

    Returns
    -------
    int
        ``MARGIN`` times the measured line of the stage, at least ``FLOOR_MB``.

    Examples
    --------
    >>> stage_memory_mb("validate", 0)
    1000
    """
    base, per_thousand = PEAK_MB.get(stage, OTHER_MB)
    return max(FLOOR_MB, int(MARGIN * (base + per_thousand * vertices / 1000)))


def memory_problem(vertices, limit_mb):
    """Why a reference of ``vertices`` vertices cannot be repaired in ``limit_mb`` MB, or None when it can.

    Parameters
    ----------
    vertices : int
    limit_mb : float
        Memory the run may use (MB); 0 or less: no limit.

    Returns
    -------
    str or None
        ``"<n> vertices need about <x> GB in stage <s>, more than the <y> GB this run may use: ..."``.
    """
    if limit_mb <= 0:
        return None
    stage = max(PEAK_MB, key=lambda s: stage_memory_mb(s, vertices))
    need = stage_memory_mb(stage, vertices)
    if need <= limit_mb:
        return None
    return (f"{vertices} vertices need about {need / 1000:.1f} GB in stage {stage}, more than the "
            f"{limit_mb / 1000:.1f} GB this run may use: free memory, give the run more (posefix repair --memory "
            "GB, snakemake --resources mem_mb=MB) or repair a decimated reference")
