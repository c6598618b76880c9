"""Configuration problems as one line each: the key path, what is wrong, what is allowed.

The workflow checks its config against ``schemas/config.schema.yaml`` before anything runs; jsonschema's
own messages name the key only in a schema dump many lines below (``1 is less than the minimum of 2``).
"""

import difflib
import os
import tempfile
from pathlib import Path

import jsonschema
import yaml

_BOOLEANS = {"true": True, "yes": True, "on": True, "false": False, "no": False, "off": False}


def config_problems(config, schema):
    """Every problem of ``config`` (dict) against the JSON ``schema`` (dict), one line each, sorted by key.

    Examples
    --------
    >>> schema = {"type": "object", "additionalProperties": False,
    ...           "properties": {"count": {"type": "integer", "minimum": 2}}}
    >>> config_problems({"count": 1, "cuont": 3}, schema)
    ['count: 1 is less than the minimum of 2', "cuont: unknown key (did you mean 'count'?)"]
    """
    validator = jsonschema.validators.validator_for(schema)(schema)
    lines = []
    for error in validator.iter_errors(config):
        lines += _describe(error)
    return sorted(set(lines))


RENAMED_KEYS = {
    "baselines": ("repairs",), "repair_medial": ("medial", "repair"), "skeletal_pose": ("medial", "pose"),
    "repair_volumetric": ("volumetric", "repair"), "volumetric_pose": ("volumetric", "pose"),
    "volumetric_animate": ("volumetric", "animate"), "repair_contact": ("contact", "repair"),
    "downstream.baselines": ("downstream", "repairs"),
}
"""Config keys renamed in 2026-12 (old key, dotted where nested: its new place), so that each repair has one name
and one section (issue 51); the old keys are read for one release, with a notice."""

SKELETON_KEYS = ("medial", "tol", "smooth_iters", "smooth_step")
"""The settings of ``skeletal_pose`` that are now ``medial.skeleton``'s (the skeletal mesh's, shared by the medial
repair and the authoring)."""


def renamed_config(config):
    """``config`` (dict) with the keys of :data:`RENAMED_KEYS` in their new places (their values over what is there)
    and one notice line per old key found, ``(dict, list of str)``; ``config`` is not changed.

    Examples
    --------
    >>> new, notices = renamed_config({"baselines": [], "skeletal_pose": {"tol": 0.2, "tau": 1.0},
    ...                                "medial": {"pose": {"tau": 0.5, "rig": None}}})
    >>> new
    {'medial': {'pose': {'tau': 1.0, 'rig': None}, 'skeleton': {'tol': 0.2}}, 'repairs': []}
    >>> notices[0]
    "posefix: config key 'baselines' is now 'repairs' (the old key goes in the next release)"
    """
    out, notices = dict(config), []
    for old, new in RENAMED_KEYS.items():
        section, _, key = old.rpartition(".")
        holder = out.get(section) if section else out
        if not isinstance(holder, dict) or key not in holder:
            continue
        holder = dict(holder)
        value = holder.pop(key)
        out = merged({k: v for k, v in out.items() if k != section}, {section: holder}) if section else holder
        moved = {new[-1]: value}
        if old == "skeletal_pose" and isinstance(value, dict):
            moved = {"pose": {k: v for k, v in value.items() if k not in SKELETON_KEYS},
                     "skeleton": {k: v for k, v in value.items() if k in SKELETON_KEYS}}
        for name in reversed(new[:-1]):
            moved = {name: moved}
        out = merged(out, moved)
        place = ".".join(new) + (" and medial.skeleton" if old == "skeletal_pose" else "")
        notices.append(f"posefix: config key '{old}' is now '{place}' (the old key goes in the next release)")
    return out, notices


def nested(config):
    """``config`` (dict) with its dotted keys as nested sections, merged with the sections it has (:func:`merged`).

    Examples
    --------
    >>> nested({"poses": "a", "fit.batch": 64, "fit": {"eps_rel": 1e-3}, "verify.finish": "snap"})
    {'poses': 'a', 'fit': {'batch': 64, 'eps_rel': 0.001}, 'verify': {'finish': 'snap'}}
    """
    out = {}
    for key, value in config.items():
        first, *rest = key.split(".")
        for name in reversed(rest):
            value = {name: value}
        out = merged(out, {first: value})
    return out


def merged(base, over):
    """``base`` (dict) with ``over``'s values over it, a section (dict) in both merged key by key, dict (neither is
    changed)."""
    out = dict(base)
    for key, value in over.items():
        out[key] = merged(out[key], value) if isinstance(value, dict) and isinstance(out.get(key), dict) else value
    return out


def folder_problem(path):
    """Why no file can be written under the folder ``path`` (str), or None: a folder is made and removed in it, or,
    where it does not exist yet, in its nearest parent that does (the run would make it there).

    Examples
    --------
    >>> folder_problem("/proc/posefix-results")
    '/proc/posefix-results cannot be made: /proc takes no new folder (No such file or directory)'
    """
    nearest = Path(os.path.abspath(path))
    while not nearest.exists():
        nearest = nearest.parent
    if not nearest.is_dir():
        return f"{path} cannot be made: {nearest} is a file"
    try:
        os.rmdir(tempfile.mkdtemp(prefix=".posefix-", dir=nearest))
    except OSError as exc:
        return f"{path} cannot be made: {nearest} takes no new folder ({exc.strerror or exc})"
    return None


def folder_problems(config, name, keys=("results", "reports")):
    """One line per folder of the library ``name`` under ``config``'s ``keys`` (``results/<name>``,
    ``reports/<name>``) that cannot be written (:func:`folder_problem`)."""
    return [f"{key}={config[key]}: {problem}" for key in keys
            if (problem := folder_problem(f"{config[key]}/{name}"))]


def typed_by_schema(value, schema):
    """``value`` with the text scalars that Snakemake's ``--config`` leaves inside nested values turned into the
    types ``schema`` allows there.

    Snakemake reads ``--config section={'key': 5}`` with YAML's base loader: every scalar inside is text. Each text
    scalar becomes, in this order, the first of the schema's types at its place that reads it: null (``null``, ``~``),
    boolean (``true``/``false``, ``yes``/``no``, ``on``/``off``), integer, number, array (``[a, b]`` or ``a,b``);
    otherwise it stays text (and the schema check names it when text is not allowed there). Values that are not text
    (config.yaml's, Snakemake's typed top-level ones) are kept.

    Parameters
    ----------
    value : object
        A config value (a dict for the whole config).
    schema : dict
        The JSON schema at the same place.

    Returns
    -------
    object

    Examples
    --------
    >>> schema = {"properties": {"fit": {"properties": {"tol": {"type": "number"}, "opencl": {"type": "boolean"}}},
    ...                          "repairs": {"type": "array", "items": {"type": "string"}}}}
    >>> typed_by_schema({"fit": {"tol": "1e-05", "opencl": "false"}, "repairs": "medial,contact"}, schema)
    {'fit': {'tol': 1e-05, 'opencl': False}, 'repairs': ['medial', 'contact']}
    """
    if isinstance(value, (dict, list)):
        schema = _alternative(schema, "object" if isinstance(value, dict) else "array")
    if isinstance(value, dict):
        properties, extra = schema.get("properties", {}), schema.get("additionalProperties")
        return {k: typed_by_schema(v, properties.get(k, extra if isinstance(extra, dict) else {}))
                for k, v in value.items()}
    if isinstance(value, list):
        return [typed_by_schema(v, schema.get("items", {})) for v in value]
    if not isinstance(value, str):
        return value
    types = _types(schema) + [t for alternative in _alternatives(schema) for t in _types(alternative)]
    return _read_text(value.strip(), types, schema)


def _types(schema):
    """The JSON type names that ``schema`` names itself (not in its alternatives), a list."""
    types = schema.get("type", [])
    return [types] if isinstance(types, str) else list(types)


def _alternatives(schema):
    """The alternatives of ``schema`` (``oneOf``, then ``anyOf``), a list of schemas."""
    return schema.get("oneOf", []) + schema.get("anyOf", [])


def _alternative(schema, kind):
    """The first alternative of ``schema``'s ``oneOf``/``anyOf`` of JSON type ``kind``, else ``schema``."""
    return next((alternative for alternative in _alternatives(schema) if kind in _types(alternative)), schema)


def _read_text(text, types, schema):
    """The first reading of ``text`` that one of ``types`` (JSON schema type names, in their order of preference
    below) allows, or ``text``."""
    if "null" in types and text in ("null", "~", "None"):
        return None
    if "boolean" in types and text.lower() in _BOOLEANS:
        return _BOOLEANS[text.lower()]
    for name, kind in (("integer", int), ("number", float)):
        if name in types:
            try:
                return kind(text)
            except ValueError:
                pass
    if "array" in types and "string" not in types:
        items = yaml.safe_load(text) if text.startswith("[") else [t.strip() for t in text.split(",") if t.strip()]
        return typed_by_schema(items, schema) if isinstance(items, list) else text
    return text


def _describe(error):
    """Lines for one jsonschema error (several for several unknown keys)."""
    path = ".".join(str(p) for p in error.absolute_path)
    prefix = f"{path}." if path else ""
    if error.validator == "additionalProperties" and isinstance(error.instance, dict):
        allowed = list(error.schema.get("properties", {}))
        return [f"{prefix}{key}: unknown key{_suggestion(key, allowed)}" for key in error.instance
                if key not in allowed]
    if error.validator == "enum":
        return [f"{path}: {error.instance!r} is not one of {', '.join(map(repr, error.validator_value))}"]
    if error.validator == "type":
        return [f"{path}: {error.instance!r} is not of type {error.validator_value}"]
    if error.validator == "pattern":
        return [f"{path}: {error.instance!r} is not a plain name (letters, digits, '.', '_' and '-', not starting "
                "with '.')"]
    return [f"{path or '(top level)'}: {error.message}"]


def _suggestion(key, allowed):
    close = difflib.get_close_matches(key, allowed, n=1)
    if close:
        return f" (did you mean {close[0]!r}?)"
    return f" (allowed: {', '.join(allowed)})" if len(allowed) <= 12 else ""
