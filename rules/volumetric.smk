# S4 pose authoring: a reference mesh and a pose script -> a pose library (stages/volumetric_pose.py). Not part
# of `rule all`: run `snakemake author_volumetric`, then repair the result with
# `snakemake --config library=<volumetric_pose.out>/<script name>`.

VOLUMETRIC = config["volumetric_pose"]
VOLUMETRIC_SCRIPT = VOLUMETRIC["script"] or str(Path(workflow.basedir) / "poses" / "demo-limb-volumetric.yaml")
VOLUMETRIC_MESH = VOLUMETRIC["mesh"] or f"{config['demo']['folder']}/{demo.REFERENCE_NAME}{demo.REFERENCE_SUFFIX}"
VOLUMETRIC_NAME = Path(VOLUMETRIC_SCRIPT).name.split(".")[0]
VOLUMETRIC_AUTHORED = f"{config['results']}/authored/{VOLUMETRIC_NAME}"


rule author_volumetric:
    input:
        mesh=VOLUMETRIC_MESH,
        script=VOLUMETRIC_SCRIPT,
    output:
        library=directory(f"{VOLUMETRIC['out']}/{VOLUMETRIC_NAME}"),
        artifact=f"{VOLUMETRIC_AUTHORED}/volumetric_pose.h5",
    params:
        name=VOLUMETRIC_NAME,
        options=" ".join(f"--{key.replace('_', '-')} {VOLUMETRIC[key]}" for key in ("tet_vertices", "iterations", "frames")),
        python=PYTHON,
        script=stage_script("volumetric_pose"),
    threads: VOLUMETRIC["threads"]
    log:
        f"{VOLUMETRIC_AUTHORED}/volumetric_pose.log",
    benchmark:
        f"{VOLUMETRIC_AUTHORED}/volumetric_pose.tsv"
    shell:
        "{params.python:q} {params.script:q} --mesh {input.mesh:q} --script {input.script:q} --out {output.library:q}"
        " --artifact {output.artifact:q} --name {params.name:q} {params.options} --threads {threads} --log {log:q}"
