# posefix: repair self-intersections in a pose library by space-time integration (S0).
# Data flow, one pose at a time after the library is validated:
#   demo (only without --config library=...) or unpack (a USD or glTF library, rules/containers.smk)
#   -> validate -> keyframes -> classify -> constraints -> fit -> integrate -> verify -> export (the repaired
#   mesh), render (report figures) and downstream (Gauss-Newton check of original vs repaired pose, S0 §5, with
#   its figure); then summary and overview over all poses, and for a USD or glTF library pack (the repaired
#   poses back in the file). Beside space-time, per pose, the other repairs of config `repairs`: medial
#   (rules/medial.smk), volumetric (rules/volumetric.smk) and contact (rules/contact.smk).
#   `snakemake --report reports/<library>/report.html` collects the report() outputs (captions in rules/captions/).
# Beside it, `snakemake skeletal_pose` (rules/medial.smk) authors a pose library from a rig file, and
# `snakemake volumetric_pose` (rules/volumetric.smk) from a pose script of handle moves.
# Rules (rules/<topic>.smk) only wire stage scripts (stages/<rule>.py); the math is in lib/posefix/.
from snakemake.utils import min_version

min_version("9.0")


configfile: os.path.join(workflow.basedir, "config.yaml")


include: "rules/common.smk"
include: "rules/library.smk"
include: "rules/containers.smk"
include: "rules/spacetime.smk"
include: "rules/verify.smk"
include: "rules/downstream.smk"
include: "rules/report.smk"
include: "rules/medial.smk"
include: "rules/volumetric.smk"
include: "rules/contact.smk"


report: "rules/captions/workflow.rst"


if workflow.is_main_process:  # the jobs of this run read the code fingerprints instead of the code
    CODE.save()


wildcard_constraints:
    pose="|".join(re.escape(p) for p in POSES),


localrules:
    all,
    summary,
    overview,


rule all:
    default_target: True
    input:
        get_final_output(),
