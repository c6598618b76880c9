"""The 3D viewer page of a library (``reports/<library>/viewer.html``): one self-contained, offline HTML file.

Every pose's target, its repairs (space-time and the other repairs) and the reference, drawn with three.js (vendored,
``vendor/three/``) under one camera; intersecting faces coloured as in the report's renders, the deviation heat map
on the report's scale, ``V_C`` / free / pass-through regions, a pose list with each pose's status.

The meshes keep their vertex order and faces: the faces are stored once per library (all poses share them), the
positions of each mesh as the bits of their float32 values XOR those of a base mesh (the reference for the target,
the target for a repair: the unchanged coordinates become zeros), byte planes apart, deflated and in base64
(:func:`encode_array`); the page decodes them exactly (``page/viewer.js``).
"""

import base64
import html
import json
import re
import zlib

import numpy as np
from matplotlib import colormaps
from matplotlib.colors import to_hex

from posefix.report.figures import CONSTRAINED, FLAG_COLORS, FREE, HEAT_MAP, heat_limit
from posefix.report.rasterizer import DISTORTED, HIGHLIGHT, SECONDARY, SURFACE, camera
from posefix.report.tables import STATUS_COLORS
from posefix.verify.flags import REPLACED_PASS_THROUGH

LEVEL = 9
"""zlib compression level (fixed: the same inputs give the same page)."""
IN_CONSTRAINED, IN_PASS_THROUGH = 1, 2
"""Bits of a vertex's region code in the page: in ``V_C``; copied from the target by the pass-through fallback."""


def encode_array(a):
    """An array's little-endian bytes, byte planes apart (all first bytes, then all second bytes, ...), deflated
    (zlib, :data:`LEVEL`), in base64, str."""
    a = np.ascontiguousarray(a)
    planes = a.astype(a.dtype.newbyteorder("<"), copy=False).view(np.uint8).reshape(-1, a.dtype.itemsize).T
    return base64.b64encode(zlib.compress(planes.tobytes(), LEVEL)).decode("ascii")


def decode_array(text, dtype, shape):
    """Inverse of :func:`encode_array`: the array of ``dtype`` and ``shape`` (what the page's decoder computes)."""
    dtype = np.dtype(dtype).newbyteorder("<")
    planes = np.frombuffer(zlib.decompress(base64.b64decode(text)), np.uint8).reshape(dtype.itemsize, -1)
    return np.ascontiguousarray(planes.T).view(dtype).reshape(shape)


def position_bits(V):
    """The bits of ``V`` (n, 3) as little-endian float32 values, (n, 3) uint32."""
    return np.asarray(V, dtype="<f4").view("<u4")


def encode_positions(V, base=None):
    """Positions ``V`` (n, 3) as float32, XOR the float32 bits of ``base`` (n, 3) when given, by
    :func:`encode_array`, str."""
    bits = position_bits(V)
    return encode_array(bits if base is None else bits ^ position_bits(base))


def decode_positions(text, n, base=None):
    """Inverse of :func:`encode_positions`: ``V`` as float32, (n, 3)."""
    bits = decode_array(text, "<u4", (n, 3))
    return (bits if base is None else bits ^ position_bits(base)).view("<f4")


def mesh_record(name, V, hit, reference_hit, base=None, distorted=None):
    """One mesh of the page, dict.

    Parameters
    ----------
    name : str
        ``target``, ``space-time``, another repair's name or ``reference``.
    V : (n, 3) float
    hit : (m,) bool
        Its intersecting faces.
    reference_hit : (m,) bool
        The reference's (the mesh's other intersecting faces are new).
    base : (str, (n, 3) float), optional
        The mesh its positions are stored against (:func:`encode_positions`), by name and positions.
    distorted : (m,) bool, optional
        Its faces stretched or crushed beyond the distortion limit (:func:`posefix.mesh.distortion.distorted_faces`);
        none by default.

    Returns
    -------
    dict
        ``name``, ``base`` (None without), ``X`` (positions), ``hit`` and ``distorted`` (faces as packed bits,
        :func:`encode_array`), ``faces``, ``new`` and ``distorted_count`` (counts of intersecting, new
        intersecting and distorted faces).
    """
    distorted = np.zeros(len(hit), dtype=bool) if distorted is None else distorted
    return {"name": name, "base": None if base is None else base[0],
            "X": encode_positions(V, None if base is None else base[1]), "hit": encode_array(np.packbits(hit)),
            "faces": int(hit.sum()), "new": int((hit & ~reference_hit).sum()),
            "distorted": encode_array(np.packbits(distorted)), "distorted_count": int(distorted.sum())}


def pose_record(name, status, meshes, mask, replaced, deviation):
    """One pose of the page, dict.

    Parameters
    ----------
    name : str
    status : (str, str)
        Its status and reason (:func:`posefix.report.tables.pose_status`).
    meshes : list of dict
        :func:`mesh_record` of the target and the repairs, in order (the target first).
    mask : (n,) bool
        ``V_C``.
    replaced : (n,) uint8
        The space-time repair's fallback flags per vertex (:mod:`posefix.verify.flags`).
    deviation : (n,) float
        The space-time repair's deviation from the target / bbox diagonal: sets the heat map's scale as in the
        report's figure (:func:`posefix.report.figures.heat_limit`).
    """
    regions = mask * IN_CONSTRAINED + ((replaced & REPLACED_PASS_THROUGH) > 0) * IN_PASS_THROUGH
    return {"name": name, "status": status[0], "reason": status[1], "meshes": meshes,
            "regions": encode_array(regions.astype(np.uint8)), "heat_limit": heat_limit(deviation)}


def page_data(library, reference, F, poses, diagonal, bounds, limit=4.0):
    """Everything the page shows, JSON-ready dict.

    Parameters
    ----------
    library : str
    reference : (n, 3) float and (m,) bool
        The reference's positions and intersecting faces.
    F : (m, 3) int
        Faces of every mesh.
    poses : list of dict
        :func:`pose_record` of each pose, in library order.
    diagonal : float
        The reference's bounding-box diagonal (length unit of the deviations).
    bounds : (2, 3) float
        Lowest and highest coordinates of every mesh of the page: the camera's first view shows them all, from
        the side of the report's renders (:func:`posefix.report.rasterizer.camera`).
    limit : float
        The distortion limit of the meshes' ``distorted`` faces (the legend's).
    """
    V, hit = reference
    R = camera(V)
    center = np.mean(bounds, axis=0)
    corners = np.array([[bounds[i][0], bounds[j][1], bounds[k][2]] for i in (0, 1) for j in (0, 1) for k in (0, 1)])
    colors = {"surface": SURFACE, "highlight": HIGHLIGHT, "secondary": SECONDARY, "constrained": CONSTRAINED,
              "free": FREE, "pass_through": FLAG_COLORS[REPLACED_PASS_THROUGH], "distorted": DISTORTED}
    return {"library": library, "vertices": len(V), "face_count": len(F), "faces": encode_array(F.astype("<u4")),
            "reference": mesh_record("reference", V, hit, hit), "poses": poses, "diagonal": float(diagonal),
            "distortion_limit": float(limit),
            "view": {"center": center.tolist(), "up": R[1].tolist(), "toward": R[2].tolist(),
                     "extent": np.abs((corners - center) @ R[:2].T).max(axis=0).tolist()},
            "colors": {k: to_hex(c) for k, c in colors.items()}, "status_colors": STATUS_COLORS,
            "heat": {"map": HEAT_MAP, "colors": [to_hex(c) for c in colormaps[HEAT_MAP](np.linspace(0, 1, 256))]}}


def data_url(script):
    """A JavaScript module as a data: URL, str."""
    return "data:text/javascript;base64," + base64.b64encode(script.encode()).decode("ascii")


def viewer_html(data, files):
    """The page, str: the template with the data, the script and three.js inlined.

    Parameters
    ----------
    data : dict
        :func:`page_data`.
    files : dict of str -> str
        The text of :data:`posefix.report.contents.VIEWER_FILES` by key.
    """
    imports = {"three": data_url(files["three"]),
               "three/addons/controls/OrbitControls.js": data_url(files["controls"])}
    parts = {"LIBRARY": html.escape(data["library"]),
             "IMPORTMAP": json.dumps({"imports": imports}, sort_keys=True),
             "DATA": json.dumps(data, sort_keys=True, separators=(",", ":")).replace("</", "<\\/"),
             "SCRIPT": files["script"]}
    return re.sub(r"@(LIBRARY|IMPORTMAP|DATA|SCRIPT)@", lambda m: parts[m.group(1)], files["template"])
