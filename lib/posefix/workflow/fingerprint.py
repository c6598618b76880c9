"""Code fingerprints: a hash of a stage script and every posefix module it imports, directly or not.

The workflow's rules are shell commands, so Snakemake does not see their code; with the fingerprint of
each rule's stage among its params, an upgraded posefix reruns exactly the stages whose code changed
(and what depends on their outputs), and nothing else. The workflow computes them once per run
(:class:`CodeFingerprints`): each file is read and parsed once, and a cache file keyed by the files'
sizes and modification times lets the jobs of the run (and the next run) reuse them without reading
any file again.
"""

import ast
import hashlib
import json
import os
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


class CodeFingerprints:
    """Fingerprints of stage scripts over one package folder, each file read and parsed at most once.

    Parameters
    ----------
    lib : path
        The folder that holds the ``posefix`` package.
    cache : path, optional
        JSON file of every file's size, modification time, sha256 and imports, read at the start and written by
        :meth:`save`: files whose size and time are unchanged are not read again.
    """

    def __init__(self, lib, cache=None):
        self.lib, self.cache = Path(lib).resolve(), cache
        self.files = {}
        if cache is not None and Path(cache).is_file():
            try:
                self.files = json.loads(Path(cache).read_text())
            except ValueError:  # a cache cut short: start over
                self.files = {}

    def _file(self, path):
        """``{"stat": [size, mtime_ns], "sha256": hex, "imports": [module files]}`` of one file."""
        st = os.stat(path)
        entry = self.files.get(str(path))
        if entry is None or entry["stat"] != [st.st_size, st.st_mtime_ns]:
            imports = set()
            for name in imported_modules(path):
                parts = name.split(".")
                for k in range(1, len(parts) + 1):  # posefix.a.b also runs posefix/__init__ and posefix/a/__init__
                    found = module_file(".".join(parts[:k]), self.lib)
                    if found is not None:
                        imports.add(str(found))
            entry = {"stat": [st.st_size, st.st_mtime_ns], "imports": sorted(imports),
                     "sha256": hashlib.sha256(Path(path).read_bytes()).hexdigest()}
            self.files[str(path)] = entry
        return entry

    def closure(self, script):
        """Files of ``script`` and of every package module it imports, transitively, sorted (tuple of Path)."""
        seen, todo = set(), [str(Path(script).resolve())]
        while todo:
            current = todo.pop()
            if current not in seen:
                seen.add(current)
                todo += [f for f in self._file(current)["imports"] if f not in seen]
        return tuple(sorted(Path(f) for f in seen))

    def fingerprint(self, script):
        """sha256 (hex, 16 characters) of ``script`` and the package modules it imports."""
        digest = hashlib.sha256()
        for file in self.closure(script):
            name = str(file.relative_to(self.lib.parent)) if file.is_relative_to(self.lib.parent) else file.name
            digest.update(name.encode() + b"\0" + self._file(str(file))["sha256"].encode() + b"\0")
        return digest.hexdigest()[:16]

    def save(self):
        """Write the cache file (atomically), if there is one."""
        if self.cache is not None:
            Path(self.cache).parent.mkdir(parents=True, exist_ok=True)
            tmp = Path(f"{self.cache}.{os.getpid()}.tmp")
            tmp.write_text(json.dumps(self.files, sort_keys=True))
            os.replace(tmp, self.cache)


def code_fingerprint(script, lib):
    """sha256 (hex, 16 characters) of the stage ``script`` and the posefix modules under ``lib`` it imports.

    Examples
    --------
    >>> code_fingerprint("stages/verify.py", "lib")  # doctest: +SKIP
    '3f0c9a1d27b4e6a5'
    """
    return CodeFingerprints(lib).fingerprint(script)
