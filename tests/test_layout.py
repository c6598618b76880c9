"""The package layout: a mesh kernel and an I/O layer that know no method, no cycles, no stage imports, short
functions."""

import ast
import importlib.util
import re
import subprocess
import sys

from conftest import ROOT

LIB = ROOT / "lib" / "posefix"


def _module(path):
    rel = path.relative_to(LIB.parent).with_suffix("")
    parts = list(rel.parts)
    return ".".join(parts[:-1] if parts[-1] == "__init__" else parts)


def import_graph():
    """Every module of posefix -> the modules it imports (posefix's by full name, others by their name)."""
    modules = {_module(p): p for p in LIB.rglob("*.py")}
    graph = {}
    for name, path in sorted(modules.items()):
        targets = set()
        for node in ast.walk(ast.parse(path.read_text())):
            if isinstance(node, ast.Import):
                targets |= {a.name for a in node.names}
            elif isinstance(node, ast.ImportFrom):
                assert node.level == 0, f"{name}: relative import"
                targets.add(node.module)
                targets |= {f"{node.module}.{a.name}" for a in node.names if f"{node.module}.{a.name}" in modules}
        graph[name] = targets - {name}
    return graph


def test_the_mesh_kernel_imports_nothing_else_of_posefix_in_a_fresh_interpreter():
    mesh = sorted(_module(p) for p in (LIB / "mesh").glob("*.py"))
    code = ("import sys; " + "; ".join(f"import {m}" for m in mesh)
            + "; print(' '.join(sorted(m for m in sys.modules if m.startswith('posefix'))))")
    loaded = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True).stdout.split()
    assert set(mesh) <= set(loaded) and all(m in ("posefix", "posefix.mesh") or m.startswith("posefix.mesh.")
                                            for m in loaded), loaded


def test_no_module_imports_a_method_from_the_kernel_or_the_stages():
    graph = import_graph()
    for name, targets in graph.items():
        own = {t for t in targets if t.split(".")[0] == "posefix"}
        if name.startswith("posefix.mesh"):
            assert all(t == "posefix" or t.startswith("posefix.mesh") for t in own), (name, own)
        if name.startswith("posefix.io"):  # the I/O layer knows the mesh kernel, no method
            assert all(t == "posefix" or t.split(".")[1] in ("io", "mesh") for t in own), (name, own)
        assert not any(t.split(".")[0] in ("stages", "benchmarks", "conftest") for t in targets), name


ALLOWED = {
    "mesh": set(), "io": {"mesh"},
    "spacetime": {"mesh", "io"}, "verify": {"mesh"}, "medial": {"mesh", "io"}, "volumetric": {"mesh"},
    "contact": {"mesh"}, "downstream": {"mesh", "workflow"},
    "report": {"mesh", "verify", "downstream"},
    "pose_repair": {"mesh", "io", "spacetime", "verify", "report", "workflow"},
    "workflow": {"mesh", "io", "spacetime", "verify", "medial", "report", "pose_repair"},
}
"""Each part of posefix (a package, or the module pose_repair) -> the parts it may import: the diagram of
docs/architecture.md ("Packages"). downstream's workflow import is ``posefix.workflow.processes`` (workers that die
with their parent)."""


def _part(module):
    return module.split(".")[1] if module.count(".") else module


def test_each_package_imports_only_what_the_architecture_diagram_allows():
    imported = {}
    for name, targets in import_graph().items():
        if name != "posefix":
            imported.setdefault(_part(name), set()).update(
                _part(t) for t in targets if t.startswith("posefix.") and _part(t) != _part(name))
    assert set(imported) == set(ALLOWED)
    assert imported == ALLOWED  # (exactly: a part that no longer imports another leaves the table too)


def test_the_architecture_page_draws_the_allowed_imports():
    page = (ROOT / "docs" / "architecture.md").read_text()
    for part, allowed in ALLOWED.items():
        row = f"| `{part}` | {', '.join(f'`{a}`' for a in sorted(allowed)) or 'nothing of posefix'} |"
        assert row in page, row


def test_the_import_graph_has_no_cycles():
    graph = import_graph()
    graph = {m: {t for t in targets if t in graph} for m, targets in graph.items()}
    state = {}

    def visit(m, path):
        state[m] = "open"
        for t in sorted(graph[m]):
            assert state.get(t) != "open", "cycle: " + " -> ".join(path + [t])
            if t not in state:
                visit(t, path + [t])
        state[m] = "done"

    for m in sorted(graph):
        if m not in state:
            visit(m, [m])


def test_functions_are_short_with_few_parameters():
    for path in sorted(LIB.rglob("*.py")):
        for node in ast.walk(ast.parse(path.read_text())):
            if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef)):
                args = node.args
                count = (len(args.posonlyargs) + len(args.args) + len(args.kwonlyargs) + bool(args.vararg)
                         + bool(args.kwarg))
                count -= bool(args.args) and args.args[0].arg in ("self", "cls")
                where = f"{path.relative_to(LIB)}:{node.lineno} {node.name}"
                assert node.end_lineno - node.lineno + 1 <= 50, f"{where}: {node.end_lineno - node.lineno + 1} lines"
                assert count <= 8, f"{where}: {count} parameters"


def test_test_files_have_unique_names():
    """pytest imports test modules by their file name (no package __init__): two test_repair.py cannot be collected
    together."""
    names = [p.name for p in (ROOT / "tests").rglob("test_*.py")]
    assert sorted(n for n in set(names) if names.count(n) > 1) == []


def test_stages_do_not_manipulate_sys_path():
    for path in sorted((ROOT / "stages").glob("*.py")) + sorted((ROOT / "rules").glob("*.smk")):
        assert "sys.path" not in path.read_text(), path.name


def _smk_defs(path):
    """``(name, first line, lines)`` of each def of a Snakemake file: from its ``def`` line to its last non-blank
    line (the body: the lines indented deeper)."""
    lines = path.read_text().splitlines()
    for i, line in enumerate(lines):
        if line.lstrip().startswith("def "):
            indent, end = len(line) - len(line.lstrip()), i + 1
            while end < len(lines) and (not lines[end].strip() or len(lines[end]) - len(lines[end].lstrip()) > indent):
                end += 1
            while not lines[end - 1].strip():
                end -= 1
            yield line.split("def ", 1)[1].split("(", 1)[0], i + 1, end - i


def test_the_snakemake_files_hold_no_def_longer_than_five_lines():
    """The planning is Python in posefix.workflow (plan, partial_summary): the .smk files declare rules (issue 51)."""
    long = [f"{path.name}:{line} {name}: {count} lines" for path in sorted((ROOT / "rules").glob("*.smk"))
            + [ROOT / "Snakefile"] for name, line, count in _smk_defs(path) if count > 5]
    assert not long, long


def test_every_rules_log_benchmark_and_memory_come_from_one_helper_each():
    """``log: log_file(...)``, ``benchmark: benchmark_file(...)`` (posefix.workflow.plan.job_files) and
    ``resources: mem_mb=...`` on one line each: no rule spells its paths out (issue 51)."""
    spelled = [f"{path.name}:{k + 1} {line.strip()}" for path in sorted((ROOT / "rules").glob("*.smk"))
               for k, line in enumerate(path.read_text().splitlines())
               if line.strip() in ("log:", "benchmark:", "resources:")
               or line.strip().startswith(("log: ", "benchmark: ")) and "_file(" not in line]
    texts = [path.read_text() for path in (ROOT / "rules").glob("*.smk")]
    stages = sum(text.count("shell:") for text in texts)  # every rule that runs a stage (the others: old names)
    assert not spelled and sum(text.count("log: log_file(") for text in texts) == stages, spelled


SEED_LABEL = re.compile(r"\bS[014]\b")
CITATION = re.compile(r"\bS[014] (§|Eq\. |Fig\. |Table )")
"""A seed label that cites: followed by a section, equation, figure or table of its paper (``S0 §4.1``)."""


def test_seed_labels_appear_only_in_citations_and_never_in_help_text():
    """Users read the repairs' names (space-time, medial, volumetric, contact); S0/S1/S4 only cite the papers, in
    the stages, the config, its schema and the report (issue 51), and never in a stage's option help."""
    report = [path for path in (ROOT / "lib" / "posefix" / "report").rglob("*")
              if path.is_file() and "vendor" not in path.parts and path.suffix in (".py", ".js", ".html", ".css")]
    paths = [*sorted((ROOT / "stages").glob("*.py")), ROOT / "config.yaml",
             *sorted((ROOT / "schemas").glob("*.yaml")), *sorted(report)]
    loose = [f"{path.relative_to(ROOT)}:{k + 1}: {line.strip()}" for path in paths
             for k, line in enumerate(path.read_text().splitlines())
             if len(SEED_LABEL.findall(line)) > len(CITATION.findall(line))]
    assert not loose, "\n".join(loose)
    helps = []
    for path in sorted((ROOT / "stages").glob("*.py")):
        spec = importlib.util.spec_from_file_location(f"stage_{path.stem}", path)
        module = importlib.util.module_from_spec(spec)
        spec.loader.exec_module(module)
        helps += [f"{path.name} {', '.join(action.option_strings)}: {action.help}"
                  for action in module.build_parser()._actions if SEED_LABEL.search(action.help or "")]
    assert not helps, helps
