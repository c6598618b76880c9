"""The wheel's build step beyond pyproject.toml: the workflow's files, kept at the repository's top level, go into
the package as ``posefix/_workflow/`` (posefix.workflow.files), so that an installed wheel runs from any folder.
An editable install (``pip install -e``) reads them from the checkout instead."""

import shutil
import sys
from pathlib import Path

from setuptools import setup
from setuptools.command.build_py import build_py

sys.path.insert(0, str(Path(__file__).parent / "lib"))
from posefix.workflow.files import PACKAGED, WORKFLOW_FILES  # noqa: E402  (the one list of them)


class BuildWithWorkflow(build_py):
    """build_py, then the workflow's files copied under the built package (not in editable mode)."""

    def run(self):
        super().run()
        if getattr(self, "editable_mode", False):
            return
        root, target = Path(__file__).parent, Path(self.build_lib) / "posefix" / PACKAGED
        for name in WORKFLOW_FILES:
            source = root / name
            if source.is_dir():
                shutil.copytree(source, target / name, dirs_exist_ok=True,
                                ignore=shutil.ignore_patterns("__pycache__", "*.pyc"))
            else:
                target.mkdir(parents=True, exist_ok=True)
                shutil.copy2(source, target / name)


setup(cmdclass={"build_py": BuildWithWorkflow})
