"""Volumetric pose scripts: handles, rigid regions and per-pose handle moves in YAML (S4 authoring).

Format (``examples/demo-limb-volumetric.yaml``)::

    handles:                      # name -> region: the tets whose four vertices lie in an axis-aligned box
      base: {box: [[-3.6, -1, -1], [-2.6, 1, 1]]}          # [min corner, max corner], model units
      wrist: {vertices: [12, 40, 77]}                      # or point handles: reference vertex ids,
      marker: {points: [[2.9, 0.1, 0.0]]}                  # or positions inside or near the mesh
    rigid:                        # optional, name -> region (same form): moves rigidly
      forearm: {box: [[1.2, -1, -1], [2.4, 1, 1]]}
    poses:                        # name -> handle -> rotation vector in degrees about the region's rest
      bend: {tip: {rotate: [0, 0, 90], translate: [-2, 2, 0]}}   # centroid, then a translation; others stay
"""

from dataclasses import dataclass

import numpy as np

from posefix.io.errors import InputError
from posefix.io.files import read_yaml


@dataclass
class PoseScript:
    """A read pose script.

    Attributes
    ----------
    handles : dict of str -> tuple of (str, ndarray)
        Per handle, in file order: ``("box", (2, 3) float)`` (min and max corner of a region handle),
        ``("vertices", (k,) int)`` (reference vertex ids) or ``("points", (k, 3) float)`` (point handles).
    rigid : dict of str -> (2, 3) float
        Boxes of the rigid regions.
    poses : dict of str -> dict of str -> tuple of ((3,) float, (3,) float)
        Per pose and handle: rotation vector (radians) and translation (model units).
    """

    handles: dict
    rigid: dict
    poses: dict


def read_pose_script(path):
    """Read a pose script (see the module text); raises :class:`InputError` naming the file and the problem."""
    doc = read_yaml(path)
    if not isinstance(doc, dict) or not doc.get("handles") or not doc.get("poses"):
        raise InputError(path, "needs 'handles' and 'poses' (see examples/demo-limb-volumetric.yaml)")
    handles = {str(n): _handle(path, n, s) for n, s in doc["handles"].items()}
    rigid = {str(n): _box(path, f"rigid region '{n}'", s) for n, s in (doc.get("rigid") or {}).items()}
    poses = {str(n): _moves(path, n, s, handles) for n, s in doc["poses"].items()}
    return PoseScript(handles, rigid, poses)


def _handle(path, name, spec):
    if isinstance(spec, dict) and "vertices" in spec:
        ids = np.asarray(spec["vertices"])
        if ids.ndim != 1 or len(ids) == 0 or not np.issubdtype(ids.dtype, np.integer) or ids.min() < 0:
            raise InputError(path, f"handle '{name}': 'vertices' must be a list of vertex ids (integers >= 0)")
        return "vertices", ids.astype(np.int64)
    if isinstance(spec, dict) and "points" in spec:
        try:
            points = np.asarray(spec["points"], dtype=float)
            if points.ndim != 2 or points.shape[1:] != (3,) or len(points) == 0 or not np.isfinite(points).all():
                raise ValueError
        except (TypeError, ValueError):
            raise InputError(path, f"handle '{name}': 'points' must be a list of [x, y, z]") from None
        return "points", points
    return "box", _box(path, f"handle '{name}'", spec)


def _box(path, what, spec):
    try:
        box = np.asarray(spec["box"], dtype=float)
        if box.shape != (2, 3) or not np.isfinite(box).all() or np.any(box[0] >= box[1]):
            raise ValueError
    except (TypeError, KeyError, ValueError):
        raise InputError(path, f"{what}: needs 'box: [[min x, y, z], [max x, y, z]]' with min < max") from None
    return box


def _moves(path, pose, spec, handles):
    spec = spec if isinstance(spec, dict) else {}
    unknown = sorted(set(map(str, spec)) - set(handles))
    if unknown:
        raise InputError(path, f"pose '{pose}': unknown handle(s) {', '.join(unknown)}")
    moves = {}
    for name, move in spec.items():
        move = move if isinstance(move, dict) else {}
        try:
            rotate = np.radians(np.asarray(move.get("rotate", [0.0, 0.0, 0.0]), dtype=float))
            translate = np.asarray(move.get("translate", [0.0, 0.0, 0.0]), dtype=float)
            if rotate.shape != (3,) or translate.shape != (3,) or not np.isfinite(np.r_[rotate, translate]).all():
                raise ValueError
        except (TypeError, ValueError):
            raise InputError(path, f"pose '{pose}', handle '{name}': 'rotate' and 'translate' must be three "
                                   "numbers") from None
        moves[str(name)] = (rotate, translate)
    return moves
