"""Bad inputs of the posefix command, one class at a time, each with the one line it must give: the cases of
``tests/test_bad_inputs.py``, and ``docs/errors.md``, which this module writes (``python tests/bad_inputs.py >
docs/errors.md``; a test checks that it is current).

Every case runs ``posefix repair`` (or ``posefix report``) in a fresh folder holding ``lib/``, the demo limb at 362
vertices (its reference and two poses; the file cases add theirs beside them). ``{lib}`` and ``{run}`` in the
arguments and the expected line are that library folder and the folder the command runs in.
"""

import gzip
import os
import shutil
import sys
from dataclasses import dataclass, field

import numpy as np

CLASSES = ("file", "library", "config", "command line", "environment")


@dataclass(frozen=True)
class BadInput:
    """One bad input.

    Attributes
    ----------
    kind : str
        Its class (:data:`CLASSES`).
    what : str
        What is wrong, in words (the first column of docs/errors.md).
    line : str
        The one error line the command must give (``{lib}``, ``{run}``: see the module's docstring).
    args : tuple of str
        The command's arguments after ``posefix`` (file cases: none, they run together, :func:`file_run_args`).
    make : callable, optional
        ``make(lib)`` writes the bad input into the library folder (a pathlib.Path) beside the good poses.
    env : dict
        Environment variables set for the command.
    """

    kind: str
    what: str
    line: str
    args: tuple = ()
    make: object = None
    env: dict = field(default_factory=dict)


def _text(name, text):
    """A ``make`` writing ``text`` into the file ``name`` of the library (its folders made)."""
    def make(lib):
        (lib / name).parent.mkdir(parents=True, exist_ok=True)
        (lib / name).write_text(text)
    return make


def _gz(name, data):
    return lambda lib: (lib / name).write_bytes(gzip.compress(data))


def _bytes(name, data):
    return lambda lib: (lib / name).write_bytes(data)


def _folder(name):
    return lambda lib: (lib / name).mkdir()


def _link(name, target):
    return lambda lib: os.symlink(target, lib / name)


def _pose_file(name, change):
    """A ``make`` writing the first good pose, changed by ``change(V, F) -> (V, F)``, as ``name``."""
    def make(lib):
        from posefix.io.meshes import read_mesh, write_mesh
        V, F = read_mesh(lib / "demo-01.obj")
        write_mesh(lib / name, *change(V.copy(), F.copy()))
    return make


def _copy(lib, folder, names):
    """Copy the files ``names`` of the library into the folder ``folder`` beside it."""
    (lib.parent / folder).mkdir()
    for name in names:
        shutil.copy(lib / name, lib.parent / folder / name)


def _loose(lib):
    """A library ``loose/`` beside ``lib``: its reference and first pose with one vertex more, in no face."""
    from posefix.io.meshes import read_mesh, write_mesh
    for name in ("reference.obj", "demo-01.obj"):
        V, F = read_mesh(lib / name)
        write_mesh(lib.parent / "loose" / name, np.vstack([V, [[9.0, 0.0, 0.0]]]), F)


def _set(V, index, value):
    V[index] = value
    return V


FAILED = "posefix: failed in validate: {lib}/"
"""How the recap at the end of a run names a pose file that failed (the file cases)."""

FILES = [
    BadInput("file", "an OBJ face with two corners",
             FAILED + "two.obj: line 4: a face with 2 vertices (truncated file?)",
             make=_text("two.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2\n")),
    BadInput("file", "an OBJ face index before the first vertex",
             FAILED + "negative.obj: line 4: face vertex index -9 is out of range -3..-1 (a negative index counts back "
             "from the last vertex line before it)",
             make=_text("negative.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf -1 -2 -9\n")),
    BadInput("file", "an OBJ coordinate that is not a number",
             FAILED + "letter.obj: line 2: vertex coordinate 'x' is not a number",
             make=_text("letter.obj", "v 0 0 0\nv 1 0 x\nv 0 1 0\nf 1 2 3\n")),
    BadInput("file", "an OBJ of points (no face)",
             FAILED + "points.obj: no faces (3 vertices and no face: points, not a triangle mesh)",
             make=_text("points.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\n")),
    BadInput("file", "an OBJ saved as UTF-16", FAILED + "utf16.obj: binary data, not an OBJ text file",
             make=_bytes("utf16.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n".encode("utf-16"))),
    BadInput("file", "a web page saved as .obj", FAILED + "html.obj: no vertex lines ('v x y z'): not an OBJ mesh",
             make=_text("html.obj", "<html><body>404 Not Found</body></html>\n")),
    BadInput("file", "a .gz file that is not gzip",
             FAILED + "notgzip.obj.gz: not a valid gzip file: Not a gzipped file (b'v ')",
             make=_bytes("notgzip.obj.gz", b"v 0 0 0\n")),
    BadInput("file", "a gzip file cut short",
             FAILED + "cut.obj.gz: not a valid gzip file: Compressed file ended before the end-of-stream marker was "
             "reached",
             make=lambda lib: (lib / "cut.obj.gz").write_bytes(
                 gzip.compress((lib / "demo-01.obj").read_bytes())[:3000])),
    BadInput("file", "an OFF file without its counts line",
             FAILED + "nocounts.off: the header declares 0 vertices but the file has 2 vertex rows",
             make=_text("nocounts.off", "OFF\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n")),
    BadInput("file", "a binary PLY cut short", FAILED + "short.ply: cannot be read as PLY: PLY is unexpected length!",
             make=_bytes("short.ply", b"ply\nformat binary_little_endian 1.0\nelement vertex 3\nproperty float x\n"
                         b"property float y\nproperty float z\nelement face 1\nproperty list uchar int vertex_indices\n"
                         b"end_header\n" + np.zeros(5, np.float32).tobytes())),
    BadInput("file", "a PLY header without its end",
             FAILED + "noend.ply: the PLY header has no end_header line (a truncated file?)",
             make=_text("noend.ply", "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\n"
                        "property float z\n0 0 0\n1 0 0\n0 1 0\n")),
    BadInput("file", "a PLY of quads",
             FAILED + "quads.ply: 1 faces in the file became 2 triangles: only triangle meshes are supported",
             make=_text("quads.ply", "ply\nformat ascii 1.0\nelement vertex 4\nproperty float x\nproperty float y\n"
                        "property float z\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n"
                        "0 0 0\n1 0 0\n1 1 0\n0 1 0\n4 0 1 2 3\n")),
    BadInput("file", "a pose with one vertex more", FAILED + "more.obj: 363 vertices, the reference has 362",
             make=_pose_file("more.obj", lambda V, F: (np.vstack([V, V[:1]]), F))),
    BadInput("file", "a pose with an infinite coordinate",
             FAILED + "inf.obj: 1 vertices have NaN or infinite coordinates (first: vertex 5)",
             make=_pose_file("inf.obj", lambda V, F: (_set(V, (5, 2), np.inf), F))),
    BadInput("file", "a link to no file",
             "posefix: warning: {lib}/dangling.obj: a link to nowhere.obj: No such file or directory; left out of the "
             "library", make=_link("dangling.obj", "nowhere.obj")),
]

LIBRARY = [
    BadInput("library", "an empty folder",
             "posefix: error: {run}/empty: no mesh files (.obj, .ply, .off, optionally .gz)",
             args=("repair", "{run}/empty"), make=lambda lib: (lib.parent / "empty").mkdir()),
    BadInput("library", "poses only in a subfolder",
             "posefix: error: {run}/nested: no mesh files (.obj, .ply, .off, optionally .gz)",
             args=("repair", "{run}/nested"), make=lambda lib: shutil.copytree(lib, lib.parent / "nested" / "sub")),
    BadInput("library", "a folder that does not exist",
             "posefix: error: {run}/nowhere: not a folder, nor a USD, glTF or Alembic file (.usd, .usda, .usdc, .usdz, "
             ".gltf, .glb, .abc)", args=("repair", "{run}/nowhere")),
    BadInput("library", "a text file as the library",
             "posefix: error: {lib}/notes.txt: not a folder, nor a USD, glTF or Alembic file (.usd, .usda, .usdc, "
             ".usdz, .gltf, .glb, .abc)", args=("repair", "{lib}/notes.txt"), make=_text("notes.txt", "poses")),
    BadInput("library", "a reference and no pose", "posefix: error: {run}/alone: no target poses besides the reference",
             args=("repair", "{run}/alone"), make=lambda lib: _copy(lib, "alone", ["reference.obj"])),
    BadInput("library", "two references",
             "posefix: error: {lib}: several reference candidates (reference.obj, second-reference.obj); set "
             "'reference' in the config", args=("repair", "{lib}"),
             make=_pose_file("second-reference.obj", lambda V, F: (V, F))),
    BadInput("library", "two poses of one name",
             "posefix: error: {lib}/demo-01.ply: same pose name 'demo-01' as demo-01.obj",
             args=("repair", "{lib}"), make=_pose_file("demo-01.ply", lambda V, F: (V, F))),
    BadInput("library", "a USD file with no mesh",
             "posefix: error: {run}/empty.usda: no mesh (UsdGeom.Mesh prim) in the file",
             args=("repair", "{run}/empty.usda"), make=_text("../empty.usda", "#usda 1.0\n")),
    BadInput("library", "a glTF file that is not JSON",
             "posefix: error: {run}/broken.gltf: cannot be read as glTF: Expecting property name enclosed in double "
             "quotes: line 1 column 2 (char 1)",
             args=("repair", "{run}/broken.gltf"), make=_text("../broken.gltf", "{not json")),
    BadInput("library", "a reference named that is not in the folder",
             "posefix: error: {lib}: reference 'nosuch.obj' not found",
             args=("repair", "{lib}", "--config", "reference=nosuch.obj")),
    BadInput("library", "a pose named that is not in the folder", "posefix: error: {lib}: pose(s) not found: nosuch",
             args=("repair", "{lib}", "--config", "poses=demo-01,nosuch")),
    BadInput("library", "a reference with a vertex in no face",
             "posefix: error: {run}/loose/reference.obj: reference has 1 vertices in no face (362): a loose vertex has "
             "no surface to move with (remove it from the library's meshes)",
             args=("repair", "{run}/loose"), make=_loose),
]

CONFIG = [
    BadInput("config", entry, f"posefix: error: config: {line}", args=("repair", "{lib}", "--config", entry))
    for entry, line in [
        ("fit.batch=0", "fit.batch: 0 is less than the minimum of 1"),
        ("verify.finish=rigid", "verify.finish: 'rigid' is not one of 'contact', 'snap'"),
        ("repairs=[medial,shape]", "repairs.1: 'shape' is not one of 'medial', 'volumetric', 'contact'"),
        ("downstream.alphas=abc", "downstream.alphas.0: 'abc' is not of type number"),
        ("fitt.batch=64", "fitt: unknown key (did you mean 'fit'?)"),
        ("fit.eps_rel=-1", "fit.eps_rel: -1.0 is less than the minimum of 0"),
        ("integrate.rtol=0", "integrate.rtol: 0.0 is less than or equal to the minimum of 0"),
        ("verify.free_goal=positional", "verify.free_goal: 'positional' is not one of 'elastic', 'blend', 'target', "
                                        "'integrated'"),
        ("summary.distortion_limit=0.5", "summary.distortion_limit: 0.5 is less than or equal to the minimum of 1"),
        ("keep_intermediates=maybe", "keep_intermediates: 'maybe' is not of type boolean"),
        ("classify.exclude=nosuch", "classify.exclude: 'nosuch' is not of type object"),
        ("contact.dhat=big", "contact.dhat: 'big' is not of type number"),
    ]
]

COMMAND_LINE = [
    BadInput("command line", " ".join(["posefix", *args]).replace("{lib}", "<lib>").replace("{run}", "<run>"),
             f"posefix: error: {line}", args=args)
    for args, line in [
        ((), "the following arguments are required: command (see posefix --help)"),
        (("repiar", "{lib}"), "argument command: invalid choice: 'repiar' (choose from 'repair', 'report') (see "
                              "posefix --help)"),
        (("repair", "{lib}", "--cores", "abc"), "argument --cores: invalid int value: 'abc' (see posefix repair "
                                                "--help)"),
        (("repair", "{lib}", "--cores", "1.5"), "argument --cores: invalid int value: '1.5' (see posefix repair "
                                                "--help)"),
        (("repair", "{lib}", "--memory", "lots"), "argument --memory: invalid float value: 'lots' (see posefix repair "
                                                  "--help)"),
        (("repair", "{lib}", "--frobnicate"), "unrecognized arguments: --frobnicate (see posefix --help)"),
        (("repair", "{lib}", "{lib}"), "unrecognized arguments: {lib} (see posefix --help)"),
        (("repair", "{lib}", "--config"), "argument --config: expected at least one argument (see posefix repair "
                                          "--help)"),
        (("repair", "{lib}", "--profile"), "argument --profile: expected one argument (see posefix repair --help)"),
        (("repair", "{lib}", "--config", "=x"), "--config =x: the key before = is not a config key (KEY=VALUE, e.g. "
                                                "fit.batch=64)"),
        (("repair", "{lib}", "--profile", "{run}"), "--profile {run}: the folder has no config.yaml (a Snakemake "
                                                    "profile's settings)"),
        (("report", "{lib}"), "WorkflowError: File reports/lib/figures/demo-01/renders.png marked for report but "
                              "does not exist."),
    ]
]

ENVIRONMENT = [
    BadInput("environment", "results= a file",
             "posefix: error: config: results=lib/demo-01.obj: lib/demo-01.obj/lib cannot be made: {lib}/demo-01.obj "
             "is a file", args=("repair", "{lib}", "--config", "results=lib/demo-01.obj")),
    BadInput("environment", "reports= where no folder can be made",
             "posefix: error: config: reports=/proc/posefix: /proc/posefix/lib cannot be made: /proc takes no new "
             "folder (No such file or directory)", args=("repair", "{lib}", "--config", "reports=/proc/posefix")),
    *[BadInput("environment", f"the library's {key} folder a file",
               f"posefix: error: config: {key}={key}: {key}/lib cannot be made: {{run}}/{key}/lib is a file",
               args=("repair", "{lib}"), make=_text(f"../{key}/lib", "")) for key in ("results", "reports")],
    BadInput("environment", ".snakemake a file in the folder run in",
             "posefix: error: FileExistsError: [Errno 17] File exists: '.snakemake'", args=("repair", "{lib}"),
             make=_text("../.snakemake", "")),
    BadInput("environment", "XDG_CACHE_HOME where no folder can be made",
             "posefix: error: FileNotFoundError: [Errno 2] No such file or directory: '/proc/posefix-cache'",
             args=("repair", "{lib}"),
             env={"XDG_CACHE_HOME": "/proc/posefix-cache"}),
    BadInput("environment", "a folder to run in that takes no new folder",
             "posefix: error: /proc: the run's log folder posefix-logs cannot be made here (No such file or "
             "directory); run posefix in a folder you can write", args=("repair", "{lib}"), env={"CWD": "/proc"}),
    BadInput("environment", "posefix-logs a file in the folder run in",
             "posefix: error: {run}: the run's log folder posefix-logs cannot be made here (File exists); run posefix "
             "in a folder you can write", args=("repair", "{lib}"), make=_text("../posefix-logs", "")),
    BadInput("environment", "SNAKEMAKE_PROFILE names no profile",
             "posefix: error: Snakemake: profile directory given (nosuch), but no profile.yaml (or config.yaml) found "
             "(a --profile or SNAKEMAKE_PROFILE that names no profile)", args=("repair", "{lib}"),
             env={"SNAKEMAKE_PROFILE": "nosuch"}),
    BadInput("environment", "integrate on a GPU that is absent",
             "posefix: error: config: integrate.device: gpu requested but no gpu OpenCL device with float64 support "
             "(auto falls back to numpy)",
             args=("repair", "{lib}", "--config", "integrate.device=gpu", "repairs=[]")),
]

CASES = FILES + LIBRARY + CONFIG + COMMAND_LINE + ENVIRONMENT


def markdown(cases=CASES):
    """docs/errors.md: the cases by class, each with its line (str)."""
    out = ["# Errors: what each bad input says", "",
           "Generated from `tests/bad_inputs.py` (`python tests/bad_inputs.py > docs/errors.md`), whose cases",
           "`tests/test_bad_inputs.py` runs: each gives this one line on the terminal (and, after a run started,",
           "`posefix: Snakemake's full output: <its log>`) and exits with an error status (1; 2 for arguments that",
           "cannot be parsed); a bad pose file leaves the library's other poses repaired (a link to no file is left",
           "out with a warning). `<lib>` is the library folder (the demo limb at 362 vertices), `<run>` the folder",
           "posefix runs in.", ""]
    for kind in CLASSES:
        out += [f"## {kind[0].upper()}{kind[1:]}", "", "| bad input | the line |", "|---|---|"]
        for case in cases:
            if case.kind == kind:
                line = case.line.replace("{lib}", "<lib>").replace("{run}", "<run>").replace("|", "\\|")
                out.append(f"| {case.what} | `{line}` |")
        out.append("")
    return "\n".join(out)


if __name__ == "__main__":
    sys.stdout.write(markdown())
