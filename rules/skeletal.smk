# S1 pose authoring: a reference mesh and a rig file -> a pose library of <pose>-ssd, <pose>-variational and
# <pose>-flow meshes (stages/skeletal_pose.py). Not part of `rule all`: run `snakemake skeletal_pose`, then repair the
# result with `snakemake --config library=<skeletal_pose.out>/<rig name>`.

AUTHOR = config["skeletal_pose"]
AUTHOR_RIG = AUTHOR["rig"] or str(Path(workflow.basedir) / "examples" / "demo-limb.yaml")
AUTHOR_MESH = AUTHOR["mesh"] or f"{config['demo']['folder']}/{demo.REFERENCE_NAME}{demo.REFERENCE_SUFFIX}"
AUTHOR_NAME = Path(AUTHOR_RIG).name.split(".")[0]
AUTHORED = f"{config['results']}/authored/{AUTHOR_NAME}"


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
        options=config_flags(AUTHOR, skip=("threads", "rig", "mesh", "out")),
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
