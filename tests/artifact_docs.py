"""The dataset tables of ``docs/artifacts.md``, written from ``schemas/artifacts.yaml`` (units and description of every
dataset, which the stages also store as the datasets' attributes), so that each dataset is described once:
``python tests/artifact_docs.py`` rewrites them in place; ``tests/test_stages.py`` checks that they are current. The
prose around them (what the stage does, its metrics and timings) is written by hand."""

import re
from pathlib import Path

import yaml

ROOT = Path(__file__).resolve().parents[1]
HEADER = ["| dataset | units | content |", "|---|---|---|"]


def stage_docs():
    """``{stage: {dataset: (units, description)}}`` of the stages that write datasets (``schemas/artifacts.yaml``)."""
    schema = yaml.safe_load((ROOT / "schemas" / "artifacts.yaml").read_text())
    return {stage: {name: tuple(doc) for name, doc in docs.items()} for stage, docs in schema.items()}


def table(docs):
    """The markdown table (list of str) of ``docs`` (name -> (units, description))."""
    return HEADER + [f"| `{name}` | {units} | {text.replace('|', '&#124;')} |" for name, (units, text) in docs.items()]


def with_tables(text, docs):
    """``text`` (docs/artifacts.md) with the table of every section ``## <stage> ...`` of ``docs`` written from it."""
    sections = re.split(r"(?m)^(?=## )", text)
    for k, section in enumerate(sections):
        stage = section[3:].split()[0] if section.startswith("## ") else None
        if stage in docs:
            lines = section.split("\n")
            start = next(i for i, line in enumerate(lines) if line.startswith("| dataset |"))
            end = next(i for i in range(start, len(lines) + 1) if i == len(lines) or not lines[i].startswith("|"))
            sections[k] = "\n".join(lines[:start] + table(docs[stage]) + lines[end:])
    return "".join(sections)


if __name__ == "__main__":
    page = ROOT / "docs" / "artifacts.md"
    page.write_text(with_tables(page.read_text(), stage_docs()))
