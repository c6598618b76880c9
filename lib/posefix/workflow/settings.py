"""Settings declared once: a dataclass whose fields carry their default, help, unit and bounds (``metadata``) gives
a stage its command-line options, the config schema its section, and so docs/configuration.md its table; the
library's default is the field's (issue 51: one place per setting).

A field's metadata: ``help`` (str, lower case, no full stop), optionally ``unit`` (a key of :data:`UNITS`),
JSON-schema bounds (:data:`BOUNDS`), for a str its ``choices``, and ``cite``: where a paper gives the value (``11
in S0 §4.1``), which the schema's description says and the option's help does not. A bool is a ``--name``/``--no-name``
pair; a tuple a list (``0.5,1``: its metadata gives the ``items`` type, their ``item_bounds`` and ``minItems``).

Examples
--------
>>> from dataclasses import dataclass, field
>>> @dataclass
... class Demo:
...     step: float = field(default=0.5, metadata={"help": "step of the flow", "unit": "d", "exclusiveMinimum": 0})
>>> schema_properties(Demo)
{'step': {'type': 'number', 'exclusiveMinimum': 0, 'default': 0.5, 'description': 'Step of the flow, relative to the bbox diagonal d.'}}
"""

import argparse
from dataclasses import fields

UNITS = {"d": "relative to the bbox diagonal d"}
"""What a setting's ``unit`` says, in words."""

BOUNDS = ("minimum", "exclusiveMinimum", "maximum", "exclusiveMaximum")
"""The JSON-schema bounds a field's metadata may give."""

_TYPES = {float: ("number", float), int: ("integer", int), bool: ("boolean", None), str: ("string", str),
          tuple: ("array", tuple)}


def add_settings_options(parser, cls, title):
    """Add an option group ``title`` (str) to ``parser`` (argparse.ArgumentParser) with one option per field of the
    dataclass ``cls``: ``--name-with-dashes``, its type, default and help (with its unit)."""
    group = parser.add_argument_group(title)
    for f in fields(cls):
        unit, kind, default = f.metadata.get("unit"), _TYPES[_type(f)][1], f.default
        how = {"action": argparse.BooleanOptionalAction} if kind is None else {"type": _bounded(kind, f.metadata)}
        if kind is tuple:
            how, default = {"type": _list_of(_bounded(f.metadata["items"], f.metadata.get("item_bounds", {})))}, list(default)
        group.add_argument(f"--{f.name.replace('_', '-')}", **how, default=default, choices=f.metadata.get("choices"),
                           help=(f.metadata["help"] + (f", {UNITS[unit]}" if unit else "")).replace("%", "%%"))


def _bounded(kind, metadata):
    """``kind`` (float, int, str) as an argparse type that also refuses a value outside the field's bounds."""
    checks = [(bound, value, test) for bound, test in (("minimum", lambda v, b: v >= b),
                                                       ("exclusiveMinimum", lambda v, b: v > b),
                                                       ("maximum", lambda v, b: v <= b),
                                                       ("exclusiveMaximum", lambda v, b: v < b))
              for value in [metadata.get(bound)] if value is not None]
    if not checks:
        return kind

    def parse(text):
        value = kind(text)
        for bound, limit, test in checks:
            if not test(value, limit):
                words = {"minimum": "at least", "exclusiveMinimum": "more than", "maximum": "at most",
                         "exclusiveMaximum": "less than"}[bound]
                raise argparse.ArgumentTypeError(f"{text}: must be {words} {limit}")
        return value

    parse.__name__ = kind.__name__  # (argparse names the type in its message)
    return parse


def _list_of(kind):
    """An argparse type: a list of ``kind`` from ``0.5,1`` or ``0.5 1``."""
    def parse(text):
        return [kind(x) for x in text.replace(",", " ").split()]

    parse.__name__ = f"list of {kind.__name__}"
    return parse


def settings_from(options, cls):
    """An instance of the dataclass ``cls`` from ``options`` (a mapping holding its fields by name: a stage's
    ``vars(args)``, or a config section; a list where the field is a tuple)."""
    return cls(**{f.name: tuple(options[f.name]) if _type(f) is tuple else options[f.name] for f in fields(cls)})


def schema_properties(cls):
    """The config schema's properties of the dataclass ``cls``: per field its type, bounds, default and description
    (dict, key order as the committed schema writes them)."""
    out = {}
    for f in fields(cls):
        unit, text = f.metadata.get("unit"), f.metadata["help"]
        kind = {"enum": list(f.metadata["choices"])} if "choices" in f.metadata else {"type": _TYPES[_type(f)][0]}
        if _type(f) is tuple:
            kind |= {"minItems": f.metadata.get("minItems", 0),
                     "items": {"type": _TYPES[f.metadata["items"]][0], **f.metadata.get("item_bounds", {})}}
        default = list(f.default) if _type(f) is tuple else f.default
        out[f.name] = {**kind, **{b: f.metadata[b] for b in BOUNDS if b in f.metadata}, "default": default,
                       "description": _sentence(text) + (f", {UNITS[unit]}" if unit else "")
                       + (f" ({f.metadata['cite']})" if "cite" in f.metadata else "") + "."}
    return out


def _sentence(text):
    """``text`` as the start of a sentence: capitalized, unless it starts with a symbol (``s: constraints ...``)."""
    return text if text[1:2] == ":" else text[0].upper() + text[1:]


def _type(f):
    """A dataclass field's type (a class, also where the annotation is a string)."""
    return {"float": float, "int": int, "bool": bool, "str": str, "tuple": tuple}.get(f.type, f.type)
