"""The settings declared by dataclasses (posefix.workflow.settings) are the schema's, the stages' options and the
library's defaults at once."""

import argparse
from dataclasses import fields

import pytest

from conftest import ROOT
from posefix.workflow.config_schema import DECLARED, declared_schema
from posefix.workflow.settings import add_settings_options, schema_properties, settings_from


def test_the_committed_schema_is_what_the_declarations_give():
    text = (ROOT / "schemas" / "config.schema.yaml").read_text()
    assert declared_schema(text) == text, (
        "schemas/config.schema.yaml is stale: python -m posefix.workflow.config_schema schemas/config.schema.yaml")


def test_a_newly_declared_setting_goes_into_the_schema_after_the_one_declared_before_it():
    text = (ROOT / "schemas" / "config.schema.yaml").read_text()
    lines = text.splitlines(keepends=True)
    line = next(k for k, t in enumerate(lines) if t.startswith("      second_iterations: "))
    assert declared_schema("".join(lines[:line] + lines[line + 1:])) == text


@pytest.mark.parametrize("cls", [cls for classes in DECLARED.values() for cls in classes], ids=lambda c: c.__name__)
def test_a_declared_section_gives_options_with_its_defaults_help_and_unit(cls):
    parser = argparse.ArgumentParser()
    add_settings_options(parser, cls, cls.__name__)
    assert settings_from(vars(parser.parse_args([])), cls) == cls()  # the library's defaults
    options = {action.dest: action for action in parser._actions if action.dest != "help"}
    properties = schema_properties(cls)
    assert set(options) == set(properties) == {f.name for f in fields(cls)}
    for f in fields(cls):
        text = f.metadata["help"]
        value = list(f.default) if isinstance(f.default, tuple) else f.default  # (a list in the config)
        assert options[f.name].default == properties[f.name]["default"] == value
        shown = options[f.name].help.replace("%%", "%")  # (argparse's escape)
        assert shown.startswith(text) and properties[f.name]["description"][1:].startswith(text[1:])
        assert ("bbox diagonal" in options[f.name].help) == ("bbox diagonal" in properties[f.name]["description"])
