"""The Blender extension's zip (``make blender-addon``): the workflow's ``blender/`` folder, with posefix's version
written into its manifest, ready for Blender's *Install from Disk* (``docs/blender.md``).

    python -m posefix.workflow.blender_addon [FOLDER]   (default: dist/)
"""

import re
import sys
import zipfile
from pathlib import Path

from posefix import __version__
from posefix.workflow.files import workflow_folder

MANIFEST = "blender_manifest.toml"


def build_addon(folder):
    """Write ``posefix-blender-<version>.zip`` into ``folder`` (made if need be): every file of the add-on, the
    manifest at the archive's root with ``version`` set to posefix's, Path of the zip."""
    source, folder = workflow_folder() / "blender", Path(folder)
    folder.mkdir(parents=True, exist_ok=True)
    out = folder / f"posefix-blender-{__version__}.zip"
    with zipfile.ZipFile(out, "w", zipfile.ZIP_DEFLATED) as archive:
        for path in sorted(p for p in source.rglob("*") if p.is_file() and "__pycache__" not in p.parts):
            name = path.relative_to(source).as_posix()
            if name == MANIFEST:
                text = re.sub(r'(?m)^version = ".*"$', f'version = "{__version__}"', path.read_text())
                archive.writestr(zipfile.ZipInfo(name, (2026, 1, 1, 0, 0, 0)), text)
            else:
                archive.write(path, name)
    return out


if __name__ == "__main__":
    print(build_addon(sys.argv[1] if len(sys.argv) > 1 else "dist"))
