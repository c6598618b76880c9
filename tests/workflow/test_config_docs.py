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

    def check(name, value, spec):  # a key (dotted) of the config and its schema: a row under its section's heading
        if "properties" in spec:
            for key, sub in value.items():
                check(f"{name}.{key}", sub, spec["properties"][key])
            return
        section, _, key = name.rpartition(".")
        start = lines.index(f"## `{section}`") if section else 0
        line = next(line for line in lines[start:] if line.startswith(f"| `{key}` |"))
        assert not line.endswith("|  |"), f"{name} has no description in the schema"

    for key, value in config.items():
        check(key, value, schema["properties"][key])
