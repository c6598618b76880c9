"""docs/configuration.md is what the schema generates, and names every key of config.yaml."""

from pathlib import Path

import yaml

from posefix.workflow.config_docs import configuration_markdown

ROOT = Path(__file__).resolve().parents[2]


def test_the_committed_configuration_page_is_the_schemas():
    schema = yaml.safe_load((ROOT / "schemas" / "config.schema.yaml").read_text())
    page = (ROOT / "docs" / "configuration.md").read_text()
    assert page == configuration_markdown(schema), (
        "docs/configuration.md is stale: python -m posefix.workflow.config_docs schemas/config.schema.yaml "
        "> docs/configuration.md")


def test_every_key_of_the_config_has_a_row_with_its_meaning():
    schema = yaml.safe_load((ROOT / "schemas" / "config.schema.yaml").read_text())
    config = yaml.safe_load((ROOT / "config.yaml").read_text())
    lines = configuration_markdown(schema).splitlines()
    for key, value in config.items():
        section = "properties" in schema["properties"][key]
        start = lines.index(f"## `{key}`") if section else 0
        for row in [f"| `{k}` |" for k in value] if section else [f"| `{key}` |"]:
            line = next(line for line in lines[start:] if line.startswith(row))
            assert not line.endswith("|  |"), f"{key}: {row} has no description in the schema"
