"""Configuration problems as one line each: the key path, what is wrong, what is allowed.

The workflow checks its config against ``schemas/config.schema.yaml`` before anything runs; jsonschema's
own messages name the key only in a schema dump many lines below (``1 is less than the minimum of 2``).
"""

import difflib

import jsonschema


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
    return [f"{path or '(top level)'}: {error.message}"]


def _suggestion(key, allowed):
    close = difflib.get_close_matches(key, allowed, n=1)
    if close:
        return f" (did you mean {close[0]!r}?)"
    return f" (allowed: {', '.join(allowed)})" if len(allowed) <= 12 else ""
