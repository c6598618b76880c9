"""HDF5 stage artifacts: atomic writing, provenance attributes, validated reading.

Every artifact (``results/<library>/<pose>/<stage>.h5``) carries root attributes

* ``stage``: the stage that wrote it, ``posefix_version``;
* ``config_sha256``: sha256 of the stage's parameters as canonical JSON (:func:`config_hash`);
* ``inputs_sha256``: sha256 over the sha256 of its input files, in order (:func:`inputs_hash`);
* ``inputs``: the input paths as given, JSON list;

a group ``timings`` whose attributes are wall seconds per sub-step, and a group ``metrics`` whose
attributes are scalar results. Datasets carry ``units`` and ``description`` attributes; the full
list per stage is in ``docs/artifacts.md``.
"""

import hashlib
import json

import h5py
import numpy as np

from posefix import __version__
from posefix.io.errors import InputError
from posefix.io.files import atomic_path, file_sha256

_COMPRESS_BYTES = 1 << 16
"""Datasets of this many bytes or more are gzip-compressed (kids-0001: its per-vertex index arrays, 0.5-0.9 MB each,
were stored raw below the former 1 MiB)."""


def config_hash(params):
    """sha256 of a JSON-serializable parameter dict, independent of key order."""
    return hashlib.sha256(json.dumps(params, sort_keys=True, default=str).encode()).hexdigest()


def inputs_hash(paths):
    """sha256 over the sha256 of each file's bytes, in the given order (names do not enter)."""
    return hashlib.sha256("".join(file_sha256(p) for p in paths).encode()).hexdigest()


def write_artifact(path, stage, datasets, *, params, inputs, timings, metrics=None, docs=None):
    """Write one stage artifact atomically.

    Parameters
    ----------
    path : str or Path
    stage : str
    datasets : dict of str -> array_like
        Names may contain ``/`` to create groups.
    params : dict
        The stage's parameters (hashed into ``config_sha256`` and stored as JSON).
    inputs : list of str
        Input files (hashed into ``inputs_sha256``).
    timings : dict of str -> float
        Wall seconds per sub-step.
    metrics : dict of str -> scalar, optional
    docs : dict of str -> (units, description), optional
        Per-dataset attributes.
    """
    docs = docs or {}
    with atomic_path(path) as tmp, h5py.File(tmp, "w") as fh:
        fh.attrs["stage"] = stage
        fh.attrs["posefix_version"] = __version__
        fh.attrs["config_sha256"] = config_hash(params)
        fh.attrs["config"] = json.dumps(params, sort_keys=True, default=str)
        fh.attrs["inputs_sha256"] = inputs_hash(inputs)
        fh.attrs["inputs"] = json.dumps([str(p) for p in inputs])
        for name, value in datasets.items():
            value = np.asarray(value)
            if value.dtype.kind == "U":  # text: variable-length UTF-8
                ds = fh.create_dataset(name, data=value.astype(object), dtype=h5py.string_dtype())
            else:
                big = value.nbytes >= _COMPRESS_BYTES
                ds = fh.create_dataset(name, data=value, compression="gzip" if big else None,
                                       compression_opts=1 if big else None, shuffle=big)
            if name in docs:
                ds.attrs["units"], ds.attrs["description"] = docs[name]
        group = fh.create_group("timings")
        for key, seconds in timings.items():
            group.attrs[key] = float(seconds)
        group = fh.create_group("metrics")
        for key, value in (metrics or {}).items():
            group.attrs[key] = value


def read_artifact(path, stage, names):
    """Read datasets from a stage artifact, checking that it is one.

    Parameters
    ----------
    path : str or Path
    stage : str
        Expected value of the ``stage`` attribute.
    names : list of str
        Datasets to load into memory.

    Returns
    -------
    data : dict of str -> ndarray
    attrs : dict
        Root attributes plus ``metrics`` (dict).

    Raises
    ------
    InputError
        Missing or unreadable file, another stage's artifact, or a missing dataset.
    """
    try:
        with h5py.File(path, "r") as fh:
            found = fh.attrs.get("stage")
            if found != stage:
                raise InputError(path, f"not a '{stage}' artifact (stage attribute: {found!r})")
            missing = [n for n in names if n not in fh]
            if missing:
                raise InputError(path, f"missing dataset(s): {', '.join(missing)}")
            data = {n: fh[n][()] for n in names}
            attrs = dict(fh.attrs)
            attrs["metrics"] = dict(fh["metrics"].attrs) if "metrics" in fh else {}
            return data, attrs
    except OSError as exc:
        raise InputError(path, f"cannot be read as HDF5: {str(exc).splitlines()[0]}") from None


def carried_metrics(metrics, stage):
    """The ``metrics`` (dict) of an intermediate ``stage``'s artifact as the artifact that reads it carries them: each
    key prefixed ``<stage>_``, so that the report reads them once the intermediate is removed (verify.h5 carries
    integrate.h5's); :func:`metrics_carried` reads them back.

    Examples
    --------
    >>> carried_metrics({"backend": "opencl", "steps_max": 9}, "integrate")
    {'integrate_backend': 'opencl', 'integrate_steps_max': 9}
    >>> metrics_carried({"integrate_backend": "opencl", "repaired_new": 0}, "integrate")
    {'backend': 'opencl'}
    """
    return {f"{stage}_{key}": value for key, value in metrics.items()}


def metrics_carried(metrics, stage):
    """The metrics of ``stage`` that an artifact's ``metrics`` (dict) carry (:func:`carried_metrics`), dict."""
    prefix = f"{stage}_"
    return {key[len(prefix):]: value for key, value in metrics.items() if key.startswith(prefix)}


def source_file(path, depth=8):
    """The file a stage artifact was made from, to name in a message about it: following each artifact's first input
    back while all its inputs are artifacts (``.h5``), the last input that is not (fit's constraints.h5 ->
    keyframes.h5 -> the target pose's mesh file). ``path`` itself where the chain cannot be followed.

    Parameters
    ----------
    path : str or Path
    depth : int
        Artifacts followed at most.

    Returns
    -------
    str or Path
    """
    current = path
    for _ in range(depth):
        try:
            with h5py.File(current, "r") as fh:
                inputs = [str(p) for p in json.loads(fh.attrs.get("inputs", "[]"))]
        except (OSError, ValueError):
            return path
        files = [p for p in inputs if not p.endswith(".h5")]
        if files or not inputs:
            return files[-1] if files else path
        current = inputs[0]
    return path


def read_repair(path, name, names):
    """:func:`read_artifact` of the artifact of other repair ``name`` (written by stage ``repair_<name>``).

    Parameters
    ----------
    path : str or Path
    name : str
        The repair, e.g. ``medial`` (stage ``repair_medial``, ``results/<library>/<pose>/medial.h5``).
    names : list of str
        Datasets to load into memory.

    Returns
    -------
    data : dict of str -> ndarray
    attrs : dict
    """
    return read_artifact(path, f"repair_{name}", names)


def repaired_poses(named_paths):
    """The repaired pose of each of other repairs' artifacts (:func:`read_repair`).

    Parameters
    ----------
    named_paths : iterable of (str, str or Path)
        (repair name, artifact path) pairs, e.g. ``[("medial", "results/lib/p/medial.h5")]``.

    Returns
    -------
    dict of str -> ndarray
        Repair name -> its dataset ``repaired``, (n, 3) float64.
    """
    return {name: read_repair(path, name, ["repaired"])[0]["repaired"] for name, path in named_paths}
