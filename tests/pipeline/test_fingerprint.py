"""Code fingerprints follow a stage script's imports through the package, and only them."""

from posefix.pipeline.fingerprint import _closure, code_fingerprint


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
    closure = {p.relative_to(lib).as_posix() for p in _closure(script.resolve(), lib.resolve()) if p != script.resolve()}
    assert closure == {"posefix/__init__.py", "posefix/a.py", "posefix/sub/__init__.py", "posefix/sub/b.py",
                       "posefix/c.py"}
    before = code_fingerprint(script, lib)
    _closure.cache_clear()
    (lib / "posefix" / "unused.py").write_text("x = 2\n")
    assert code_fingerprint(script, lib) == before
    _closure.cache_clear()
    (lib / "posefix" / "c.py").write_text("def helper(): pass  # a comment\n")  # two imports away
    assert code_fingerprint(script, lib) != before
