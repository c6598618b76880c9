"""Code fingerprints: a hash of a stage script and every posefix module it imports, directly or not.

The workflow's rules are shell commands, so Snakemake does not see their code; with the fingerprint of
each rule's stage among its params, an upgraded posefix reruns exactly the stages whose code changed
(and what depends on their outputs), and nothing else.
"""

import ast
import hashlib
from functools import lru_cache
from pathlib import Path

PACKAGE = "posefix"


def imported_modules(path):
    """Absolute names of the modules a Python file imports (``import a.b``, ``from a.b import c`` also
    yields ``a.b.c``, which may be a module), set of str."""
    tree = ast.parse(Path(path).read_bytes(), filename=str(path))
    names = set()
    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            names.update(alias.name for alias in node.names)
        elif isinstance(node, ast.ImportFrom) and node.module and node.level == 0:
            names.add(node.module)
            names.update(f"{node.module}.{alias.name}" for alias in node.names)
    return names


def module_file(name, lib):
    """The file of module ``name`` under the folder ``lib`` (``lib/posefix/a/b.py`` or
    ``lib/posefix/a/b/__init__.py``), or None when it is no module of the package."""
    parts = name.split(".")
    if parts[0] != PACKAGE:
        return None
    base = Path(lib).joinpath(*parts)
    for candidate in (base.with_suffix(".py"), base / "__init__.py"):
        if candidate.is_file():
            return candidate
    return None


@lru_cache(maxsize=None)
def _closure(path, lib):
    """Files of ``path`` and of every package module it imports, transitively, sorted (tuple of Path)."""
    seen, todo = set(), [Path(path)]
    while todo:
        current = todo.pop()
        if current in seen:
            continue
        seen.add(current)
        for name in imported_modules(current):
            parts = name.split(".")
            for k in range(1, len(parts) + 1):  # posefix.a.b also runs posefix/__init__ and posefix/a/__init__
                found = module_file(".".join(parts[:k]), lib)
                if found is not None and found not in seen:
                    todo.append(found)
    return tuple(sorted(seen))


def code_fingerprint(script, lib):
    """sha256 (hex, 16 characters) of the stage ``script`` and the posefix modules under ``lib`` it imports.

    Examples
    --------
    >>> code_fingerprint("stages/verify.py", "lib")  # doctest: +SKIP
    '3f0c9a1d27b4e6a5'
    """
    digest = hashlib.sha256()
    root = Path(lib)
    for file in _closure(Path(script).resolve(), root.resolve()):
        digest.update(str(file.relative_to(root.resolve().parent)).encode() + b"\0" + file.read_bytes() + b"\0")
    return digest.hexdigest()[:16]
