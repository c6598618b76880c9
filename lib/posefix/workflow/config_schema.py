"""The sections of ``schemas/config.schema.yaml`` that settings dataclasses declare (:mod:`posefix.workflow.settings`),
written from the dataclasses so that each setting is declared once.

``python -m posefix.workflow.config_schema schemas/config.schema.yaml`` rewrites those properties in place (one line
each, flow style); ``tests/workflow/test_config_schema.py`` checks that the committed schema is what they give.
"""

import sys

import yaml

from posefix.mesh.contact_solver import ContactSettings
from posefix.verify.contact_finish import FinishSettings
from posefix.verify.sequence import RepairSettings
from posefix.workflow.settings import schema_properties
from posefix.workflow.stage_settings import (ClassifySettings, ConstraintsSettings, DemoSettings, DownstreamSettings,
                                             FitOptions, IntegrateSettings, KeyframesSettings, MedialRepairSettings,
                                             SkeletalPoseSettings, SkeletonSettings, SummarySettings, TetMeshSettings,
                                             VolumetricAnimateSettings, VolumetricPoseSettings,
                                             VolumetricRepairSettings)

DECLARED = {
    "demo": (DemoSettings,), "keyframes": (KeyframesSettings,), "classify": (ClassifySettings,),
    "constraints": (ConstraintsSettings,), "fit": (FitOptions,), "integrate": (IntegrateSettings,),
    "verify": (RepairSettings, FinishSettings), "contact": (ContactSettings,), "downstream": (DownstreamSettings,),
    "summary": (SummarySettings,), "medial.skeleton": (SkeletonSettings,), "medial.repair": (MedialRepairSettings,),
    "medial.pose": (SkeletalPoseSettings,), "volumetric.repair": (TetMeshSettings, VolumetricRepairSettings),
    "volumetric.pose": (TetMeshSettings, VolumetricPoseSettings),
    "volumetric.animate": (TetMeshSettings, VolumetricAnimateSettings),
}
"""Config section -> the dataclasses that declare its settings (the section may hold other keys: a rule's threads, nested
sections)."""


def declared_schema(text):
    """The schema's ``text`` (str) with the properties of the :data:`DECLARED` sections as their dataclasses give
    them, str; a newly declared one goes after the one declared before it; every other line unchanged."""
    lines = text.splitlines(keepends=True)
    for section, classes in DECLARED.items():
        start, end, indent = _section(lines, section)
        k = None
        for name, prop in [item for cls in classes for item in schema_properties(cls).items()]:
            flow = yaml.safe_dump(prop, default_flow_style=True, sort_keys=False, width=10 ** 6, allow_unicode=True)
            line = f"{indent}{name}: {flow.strip()}\n"
            found = next((j for j in range(start, end) if lines[j].startswith(f"{indent}{name}: ")), None)
            if found is None:
                k, end = k + 1, end + 1
                lines.insert(k, line)
            else:
                k, lines[found] = found, line
    return "".join(lines)


def _section(lines, path):
    """``(first line, end line, indent of its properties)`` of the config section ``path`` (dotted: ``medial.repair``)
    in the schema's ``lines``: a section at depth k is at indent 2 + 4 k, its properties 4 deeper."""
    start, end = 0, len(lines)
    for depth, name in enumerate(path.split(".")):
        indent = " " * (2 + 4 * depth)
        start = next(k for k in range(start, end) if lines[k] == f"{indent}{name}:\n")
        end = next((k for k in range(start + 1, end) if lines[k].strip() and len(lines[k]) - len(lines[k].lstrip())
                    <= len(indent)), end)
    return start, end, " " * (6 + 4 * depth)


if __name__ == "__main__":
    with open(sys.argv[1]) as f:
        schema = declared_schema(f.read())
    with open(sys.argv[1], "w") as f:
        f.write(schema)
