"""One name per repair (issue 51): each of the four has its package, rules file, tests folder and report label under
one identifier, and the three compared with space-time their config section, ``repairs`` entry, stage and artifact."""

import yaml

from conftest import ROOT
from posefix.report.contents import COMPARED_REPAIRS, REPAIRS, SPACETIME
from posefix.workflow.library_repair import REPAIRS as API_REPAIRS

CONFIG = yaml.safe_load((ROOT / "config.yaml").read_text())
SCHEMA = yaml.safe_load((ROOT / "schemas" / "config.schema.yaml").read_text())
SPACETIME_STAGES = ("keyframes", "classify", "constraints", "fit", "integrate", "verify")
"""Space-time's stages: their config sections are its settings (the design card's names)."""
TOPICS = {"common", "library", "containers", "verify", "downstream", "report"}
"""The rules files that belong to no one method (verify.smk: space-time's finish and the repaired meshes' export)."""
KERNEL = {"mesh", "io", "workflow", "report", "verify", "downstream", "__pycache__"}
"""The packages under lib/posefix that are no method (verify: space-time's finish; downstream: the check)."""


def test_each_repair_has_one_identifier_across_package_rules_tests_and_report():
    methods = set(REPAIRS)
    assert {p.name for p in (ROOT / "lib" / "posefix").iterdir() if p.is_dir()} - KERNEL == methods
    assert {p.stem for p in (ROOT / "rules").glob("*.smk")} - TOPICS == methods
    assert methods <= {p.name for p in (ROOT / "tests").iterdir() if p.is_dir()}
    assert API_REPAIRS == tuple(REPAIRS.values()) and SPACETIME == "space-time"
    assert all(REPAIRS[name] == name for name in methods - {"spacetime"})  # labels are identifiers but one


def test_the_compared_repairs_share_their_name_with_their_config_section_stage_and_artifact():
    compared = list(COMPARED_REPAIRS)
    assert CONFIG["repairs"] == compared and SCHEMA["properties"]["repairs"]["items"]["enum"] == compared
    for name in compared:
        assert isinstance(CONFIG[name].get("repair"), dict), f"config {name}.repair"
        assert (ROOT / "stages" / f"repair_{name}.py").is_file()
        rules = (ROOT / "rules" / f"{name}.smk").read_text()
        assert f"rule repair_{name}:" in rules and f'f"{{RESULTS}}/{{{{pose}}}}/{name}.h5"' in rules
    assert all(stage in CONFIG for stage in SPACETIME_STAGES)
    assert "rule keyframes:" in (ROOT / "rules" / "spacetime.smk").read_text()
    common = (ROOT / "rules" / "common.smk").read_text()
    assert "REPAIR_CHOICES = COMPARED_REPAIRS" in common


def test_the_other_repairs_are_called_repairs_not_baselines():
    """``baselines`` became ``repairs`` in config, summary.json and code; the word is left only where config_check reads
    the old key for one release, and in S0 Table 1's "full solve" baseline (another concept)."""
    allowed = {ROOT / "lib" / "posefix" / "workflow" / "config_check.py": 0,
               ROOT / "lib" / "posefix" / "spacetime" / "factorization.py": 1}
    for folder, pattern in (("lib/posefix", "*.py"), ("stages", "*.py"), ("benchmarks", "*.py"), ("rules", "*.smk"),
                            ("rules/captions", "*.rst")):
        for path in (ROOT / folder).rglob(pattern):
            words = [w.strip(".,:;()`'\"") for w in path.read_text().lower().split()]
            count = sum(w in ("baseline", "baselines", "baseline's") for w in words)
            assert count == allowed.get(path, 0) or path.name == "config_check.py", f"{path}: {count} baselines"
