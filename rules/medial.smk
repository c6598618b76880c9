# The medial method (S1): the reference's skeletal mesh once per library (S1 §2, config medial.skeleton), then per
# pose the medial repair (the medial-ball flow of S1 §4 from the target, posefix.medial.repair; config medial.repair),
# compared beside space-time when config `repairs` names it. And pose authoring: a reference mesh and a rig file ->
# a pose library of <pose>-ssd, <pose>-variational and <pose>-flow meshes (stages/skeletal_pose.py, config
# medial.pose). Not part of `rule all`: run `snakemake skeletal_pose`, then repair the result with
# `snakemake --config library=<medial.pose.out>/<rig name>`.

MEDIAL = config["medial"]
AUTHOR = MEDIAL["pose"]
AUTHOR_RIG = AUTHOR["rig"] or str(Path(workflow.basedir) / "examples" / "demo-limb.yaml")
AUTHOR_MESH = AUTHOR["mesh"] or f"{config['demo']['folder']}/{demo.REFERENCE_NAME}{demo.REFERENCE_SUFFIX}"
AUTHOR_NAME = Path(AUTHOR_RIG).name.split(".")[0]
AUTHORED = f"{config['results']}/authored/{AUTHOR_NAME}"


rule skeleton:
    input:
        reference=LIBRARY.reference.path,
        checked=rules.validate_reference.output[0],
    output:
        f"{RESULTS}/skeleton.h5",
    params:
        options=config_flags(MEDIAL["skeleton"]),
        script=stage_script("skeleton"),
        code=stage_code("skeleton"),
    threads: 1
    resources: mem_mb=memory_mb("skeleton")
    log: log_file("skeleton", None)
    benchmark: benchmark_file("skeleton", None)
    conda: "../envs/posefix.yaml"
    shell:
        "python {params.script:q} --reference {input.reference:q} --out {output:q} {params.options}"
        " --threads {threads} --log {log:q}"


rule repair_medial:
    input:
        reference=LIBRARY.reference.path,
        target=pose_file,
        checked=rules.validate.output[0],
        skeleton=rules.skeleton.output[0],
    output:
        f"{RESULTS}/{{pose}}/medial.h5",
    params:
        options=config_flags(MEDIAL["repair"]),
        script=stage_script("repair_medial"),
        code=stage_code("repair_medial"),
    threads: MEDIAL["repair"]["threads"]
    resources: mem_mb=memory_mb("repair_medial")
    log: log_file("repair_medial")
    benchmark: benchmark_file("repair_medial")
    conda: "../envs/posefix.yaml"
    shell:
        "python {params.script:q} --reference {input.reference:q} --target {input.target:q}"
        " --skeleton {input.skeleton:q} --out {output:q} {params.options} --threads {threads} --log {log:q}"


rule skeletal_pose:
    input:
        mesh=AUTHOR_MESH,
        rig=AUTHOR_RIG,
    output:
        library=directory(f"{AUTHOR['out']}/{AUTHOR_NAME}"),
        artifact=f"{AUTHORED}/skeletal_pose.h5",
    params:
        script=stage_script("skeletal_pose"),
        code=stage_code("skeletal_pose"),
        name=AUTHOR_NAME,
        options=config_flags({**MEDIAL["skeleton"], **AUTHOR}, skip=("threads", "rig", "mesh", "out")),
    threads: AUTHOR["threads"]
    log: log_file("skeletal_pose", "", AUTHORED)
    benchmark: benchmark_file("skeletal_pose", "", AUTHORED)
    conda: "../envs/posefix.yaml"
    shell:
        "python {params.script:q} --mesh {input.mesh:q} --rig {input.rig:q} --out {output.library:q}"
        " --artifact {output.artifact:q} --name {params.name:q} {params.options} --threads {threads} --log {log:q}"


rule author:  # its name before 2026-12 (common.smk: RENAMED_RULES)
    input:
        rules.skeletal_pose.output,
