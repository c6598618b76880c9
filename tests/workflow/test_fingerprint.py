"""Code fingerprints follow a stage script's imports through the package, and only them."""

import posefix.workflow.fingerprint as fingerprint
from posefix.workflow.fingerprint import CodeFingerprints, code_fingerprint


def package(tmp_path):
    lib = tmp_path / "lib"
    (lib / "posefix" / "sub").mkdir(parents=True)
    files = {"posefix/__init__.py": "", "posefix/sub/__init__.py": "", "posefix/a.py": "import posefix.sub.b\n",
             "posefix/sub/b.py": "from posefix.c import helper\n", "posefix/c.py": "def helper(): pass\n",
             "posefix/unused.py": "x = 1\n"}
    for name, text in files.items():
        (lib / name).write_text(text)
    script = tmp_path / "stage.py"
    script.write_text("import numpy\nfrom posefix.a import thing\n\ndef main():\n    import posefix.sub\n")
    return lib, script


def test_the_fingerprint_changes_with_an_imported_module_and_only_then(tmp_path):
    lib, script = package(tmp_path)
    closure = {p.relative_to(lib.resolve()).as_posix() for p in CodeFingerprints(lib).closure(script)
               if p != script.resolve()}
    assert closure == {"posefix/__init__.py", "posefix/a.py", "posefix/sub/__init__.py", "posefix/sub/b.py",
                       "posefix/c.py"}
    before = code_fingerprint(script, lib)
    (lib / "posefix" / "unused.py").write_text("x = 2\n")
    assert code_fingerprint(script, lib) == before
    (lib / "posefix" / "c.py").write_text("def helper(): pass  # a comment\n")  # two imports away
    assert code_fingerprint(script, lib) != before


def test_the_cache_file_spares_reading_unchanged_files_and_sees_changed_ones(tmp_path, monkeypatch):
    lib, script = package(tmp_path)
    cache = tmp_path / "cache" / "code.json"
    first = CodeFingerprints(lib, cache)
    before = first.fingerprint(script)
    first.save()
    monkeypatch.setattr(fingerprint, "imported_modules", lambda path: 1 / 0)  # no file may be parsed again
    assert CodeFingerprints(lib, cache).fingerprint(script) == before
    monkeypatch.undo()
    (lib / "posefix" / "c.py").write_text("def helper(): return 1\n")  # another size: read again
    assert CodeFingerprints(lib, cache).fingerprint(script) != before
