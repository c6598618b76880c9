"""The sections of ``schemas/config.schema.yaml`` that settings dataclasses declare (:mod:`posefix.workflow.settings`),
written from the dataclasses so that each setting is declared once.

``python -m posefix.workflow.config_schema schemas/config.schema.yaml`` rewrites those properties in place (one line
each, flow style); ``tests/workflow/test_config_schema.py`` checks that the committed schema is what they give.
"""

import sys

import yaml

from posefix.mesh.contact_solver import ContactSettings
from posefix.spacetime.settings import (ClassifySettings, ConstraintsSettings, IntegrateSettings,
                                        KeyframesSettings)
from posefix.verify.contact_finish import FinishSettings
from posefix.verify.sequence import RepairSettings
from posefix.workflow.settings import schema_properties

DECLARED = {"keyframes": (KeyframesSettings,), "classify": (ClassifySettings,), "constraints": (ConstraintsSettings,),
            "integrate": (IntegrateSettings,), "verify": (RepairSettings, FinishSettings),
            "contact": (ContactSettings,)}
"""Config section -> the dataclasses that declare its settings (the section may hold other keys: a rule's threads, nested
sections)."""


def declared_schema(text):
    """The schema's ``text`` (str) with the properties of the :data:`DECLARED` sections as their dataclasses give
    them, str; every other line unchanged."""
    lines = text.splitlines(keepends=True)
    for section, classes in DECLARED.items():
        start = lines.index(f"  {section}:\n")
        end = next((k for k in range(start + 1, len(lines)) if lines[k].startswith("  ") and lines[k][2] != " "),
                   len(lines))
        for name, prop in [item for cls in classes for item in schema_properties(cls).items()]:
            k = next(k for k in range(start, end) if lines[k].startswith(f"      {name}: "))
            flow = yaml.safe_dump(prop, default_flow_style=True, sort_keys=False, width=10 ** 6, allow_unicode=True).strip()
            lines[k] = f"      {name}: {flow}\n"
    return "".join(lines)


if __name__ == "__main__":
    with open(sys.argv[1]) as f:
        text = f.read()
    with open(sys.argv[1], "w") as f:
        f.write(declared_schema(text))
