"""docs/configuration.md, generated from the config schema so that it cannot drift from it.

``python -m posefix.workflow.config_docs schemas/config.schema.yaml > docs/configuration.md`` writes it;
``tests/workflow/test_config_docs.py`` checks that the committed page equals what the schema gives.
"""

import json
import sys

import yaml

HEADER = """# Configuration

Every tunable of the workflow is in [config.yaml](../config.yaml), with a comment, and validated against
[schemas/config.schema.yaml](../schemas/config.schema.yaml) before anything runs (one line per problem, naming
the key). Override any of them on the command line: `--config fit="{eps_rel: 1e-3}"`, `--config
library=path/to/folder poses=a,b`. Lengths are relative to the reference's bounding-box diagonal d where the
text says so. This page is generated from the schema (`python -m posefix.workflow.config_docs
schemas/config.schema.yaml > docs/configuration.md`; a test checks it).
"""


def configuration_markdown(schema):
    """The configuration page of ``schema`` (dict, the JSON schema of config.yaml): one table per section.

    Examples
    --------
    >>> schema = {"properties": {"count": {"type": "integer", "minimum": 2, "default": 11, "description": "K."}}}
    >>> configuration_markdown(schema).splitlines()[-1]
    '| `count` | integer, ≥ 2 | `11` | K. |'
    """
    top = {k: v for k, v in schema["properties"].items() if "properties" not in v}
    lines = [HEADER, "## Top level", ""] + _table(top, "")
    for section, spec in schema["properties"].items():
        lines += _sections(section, spec)
    return "\n".join(lines) + "\n"


def _sections(name, spec):
    """The lines of section ``name`` (dotted) and of the sections nested in it: a heading, its description, a table
    of its settings (none for a section of sections only), list of str."""
    if "properties" not in spec:
        return []
    settings = {k: v for k, v in spec["properties"].items() if "properties" not in v}
    body = [spec["description"]] if "description" in spec else []
    body += ([""] if body else []) + _table(settings, "") if settings else []
    lines = ["", f"## `{name}`", ""] + body
    for key, sub in spec["properties"].items():
        lines += _sections(f"{name}.{key}", sub)
    return lines


def _table(properties, prefix):
    """Markdown table rows (list of str) of ``properties`` (key -> schema)."""
    rows = ["| key | type | default | meaning |", "|---|---|---|---|"]
    for key, spec in properties.items():
        meaning = spec.get("description", "").replace("|", "\\|").replace("\n", " ")
        rows.append(f"| `{prefix}{key}` | {_type(spec)} | `{json.dumps(spec.get('default'))}` | {meaning} |")
    return rows


def _type(spec):
    """What a value may be, in words: type or choices, and bounds."""
    if "enum" in spec:
        kind = " or ".join(f"`{v}`" for v in spec["enum"])
    elif "oneOf" in spec or "anyOf" in spec:
        kind = " or ".join(_type(s) for s in spec.get("oneOf", spec.get("anyOf")))
    else:
        kind = spec.get("type", "any")
        kind = " or ".join(kind) if isinstance(kind, list) else kind
        if kind == "array" and "items" in spec:
            kind = f"list of {_type(spec['items'])}"
    bounds = [f"{sign} {spec[key]}" for key, sign in (("minimum", "≥"), ("exclusiveMinimum", ">"),
                                                      ("maximum", "≤"), ("exclusiveMaximum", "<")) if key in spec]
    return ", ".join([kind] + bounds)


if __name__ == "__main__":
    with open(sys.argv[1]) as f:
        sys.stdout.write(configuration_markdown(yaml.safe_load(f)))
