"""Rig files: a stick-figure skeleton and its poses in YAML (format: ``examples/demo-limb.yaml``).

::

    joints:                       # name -> rest position (model units), parent (the root has none)
      root: {position: [-3, 0, 0]}
      elbow: {position: [-1, 0, 0], parent: root}
    poses:                        # name -> per-joint rotation vectors in degrees (or a list, applied
      bend: {rotations: {elbow: [0, 0, 90]}, translation: [0, 0, 0]}   # in order); root translation
"""

import numpy as np

from posefix.io.errors import InputError
from posefix.io.files import read_yaml
from posefix.medial.rig import Rig, pose_from_rotation_vectors


def read_rig(path):
    """Read a rig file.

    Parameters
    ----------
    path : str or Path

    Returns
    -------
    rig : Rig
    poses : dict of str -> RigPose
        In file order.

    Raises
    ------
    InputError
        Unreadable file, not YAML, no joints or poses, a joint without a position, an unknown or cyclic
        parent, not exactly one root, a pose naming an unknown joint, or a malformed rotation.
    """
    doc = read_yaml(path)
    if not isinstance(doc, dict) or not doc.get("joints") or not doc.get("poses"):
        raise InputError(path, "needs 'joints' and 'poses' (see examples/demo-limb.yaml)")
    rig = _rig(path, doc["joints"])
    return rig, {str(name): _pose(path, rig, name, spec) for name, spec in doc["poses"].items()}


def _rig(path, joints):
    names = [str(n) for n in joints]
    parents, rest = [], []
    for name in names:
        spec = joints[name] if isinstance(joints[name], dict) else {}
        position = np.asarray(spec.get("position", []), dtype=float)
        if position.shape != (3,) or not np.isfinite(position).all():
            raise InputError(path, f"joint '{name}': 'position' must be three numbers")
        parent = spec.get("parent")
        if parent is not None and str(parent) not in names[:len(parents)]:
            raise InputError(path, f"joint '{name}': parent '{parent}' is not a joint listed before it")
        parents.append(-1 if parent is None else names.index(str(parent)))
        rest.append(position)
    if parents.count(-1) != 1:
        raise InputError(path, f"needs exactly one root joint (without parent), found {parents.count(-1)}")
    return Rig(names=tuple(names), rest=np.array(rest), parents=np.array(parents))


def _pose(path, rig, name, spec):
    spec = spec if isinstance(spec, dict) else {}
    rotations = spec.get("rotations") or {}
    unknown = sorted(set(map(str, rotations)) - set(rig.names))
    if unknown:
        raise InputError(path, f"pose '{name}': unknown joint(s) {', '.join(unknown)}")
    try:
        radians = {str(j): np.radians(np.asarray(r, dtype=float)) for j, r in rotations.items()}
        translation = np.asarray(spec.get("translation", [0.0, 0.0, 0.0]), dtype=float)
        if translation.shape != (3,) or any(r.shape[-1:] != (3,) or r.ndim > 2 for r in radians.values()):
            raise ValueError
    except (TypeError, ValueError):
        raise InputError(path, f"pose '{name}': rotations are [x, y, z] in degrees (or lists of them), "
                               "translation [x, y, z]") from None
    return pose_from_rotation_vectors(rig, radians, translation)
