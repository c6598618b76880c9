"""Where the workflow's files are: beside the package in an installed wheel, or the checkout of an editable install.

The workflow (``Snakefile``, ``rules/``, ``stages/``, ``schemas/``, ``config.yaml``, ``profiles/``, ``envs/``,
``examples/``, and the Blender add-on's ``blender/``) keeps the repository's top-level layout; ``setup.py`` copies it
into the wheel as the package data
``posefix/_workflow/`` (:data:`WORKFLOW_FILES`). ``pip install -e`` leaves it in the checkout.
"""

from importlib import resources
from pathlib import Path

WORKFLOW_FILES = ("Snakefile", "config.yaml", "rules", "stages", "schemas", "profiles", "envs", "examples", "blender")
"""The repository's top-level files and folders that make the workflow (and the Blender add-on, which starts it),
shipped in the wheel under ``_workflow``."""

PACKAGED = "_workflow"
"""The package-data folder of the workflow in an installed wheel."""


def package_folder():
    """The folder of the imported ``posefix`` package (lib/posefix in the checkout), Path."""
    return Path(str(resources.files("posefix"))).resolve()


def workflow_folder():
    """The folder holding the workflow's Snakefile (Path): ``posefix/_workflow`` of an installed wheel, else the
    checkout the package was installed from in editable mode (two levels above the package: lib/posefix)."""
    packaged = package_folder() / PACKAGED
    return packaged if (packaged / "Snakefile").is_file() else package_folder().parents[1]
