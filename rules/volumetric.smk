# The volumetric method (S4): the reference's tet mesh once per library (S4 §2.1), then per pose the volumetric
# repair (the iterative editor fills the free region, posefix.volumetric.repair; config volumetric.repair), compared
# beside space-time when config `repairs` names it. And pose authoring: a reference mesh and a pose script -> a pose
# library (stages/volumetric_pose.py, config volumetric.pose), or marker tracks -> an animated pose library
# (stages/volumetric_animate.py, config volumetric.animate). Not part of `rule all`: run `snakemake volumetric_pose`
# or `snakemake volumetric_animate`, then repair the result with `snakemake --config library=<out>/<script or
# tracks name>`.

FILL = config["volumetric"]["repair"]


rule tet_mesh:
    input:
        reference=LIBRARY.reference.path,
        checked=rules.validate_reference.output[0],
    output:
        f"{RESULTS}/tets.h5",
    params:
        options=config_flags({"tet_vertices": FILL["tet_vertices"]}),
        script=stage_script("tet_mesh"),
        code=stage_code("tet_mesh"),
    threads: 1
    resources: mem_mb=memory_mb("tet_mesh")
    log: log_file("tet_mesh", None)
    benchmark: benchmark_file("tet_mesh", None)
    conda: "../envs/posefix.yaml"
    shell:
        "python {params.script:q} --reference {input.reference:q} --out {output:q}"
        " {params.options} --threads {threads} --log {log:q}"


rule repair_volumetric:
    input:
        reference=LIBRARY.reference.path,
        target=pose_file,
        classify=rules.classify.output[0],
        tets=rules.tet_mesh.output[0],
    output:
        f"{RESULTS}/{{pose}}/volumetric.h5",
    params:
        options=config_flags(FILL, skip=("threads", "tet_vertices")),
        script=stage_script("repair_volumetric"),
        code=stage_code("repair_volumetric"),
    threads: FILL["threads"]
    resources: mem_mb=memory_mb("repair_volumetric")
    log: log_file("repair_volumetric")
    benchmark: benchmark_file("repair_volumetric")
    conda: "../envs/posefix.yaml"
    shell:
        "python {params.script:q} --reference {input.reference:q} --target {input.target:q}"
        " --classify {input.classify:q} --tets {input.tets:q} --out {output:q} {params.options}"
        " --threads {threads} --log {log:q}"


VOLUMETRIC = config["volumetric"]["pose"]
VOLUMETRIC_SCRIPT = VOLUMETRIC["script"] or str(Path(workflow.basedir) / "examples" / "demo-limb-volumetric.yaml")
VOLUMETRIC_MESH = VOLUMETRIC["mesh"] or f"{config['demo']['folder']}/{demo.REFERENCE_NAME}{demo.REFERENCE_SUFFIX}"
VOLUMETRIC_NAME = Path(VOLUMETRIC_SCRIPT).name.split(".")[0]
VOLUMETRIC_AUTHORED = f"{config['results']}/authored/{VOLUMETRIC_NAME}"


rule volumetric_pose:
    input:
        mesh=VOLUMETRIC_MESH,
        script=VOLUMETRIC_SCRIPT,
    output:
        library=directory(f"{VOLUMETRIC['out']}/{VOLUMETRIC_NAME}"),
        artifact=f"{VOLUMETRIC_AUTHORED}/volumetric_pose.h5",
    params:
        name=VOLUMETRIC_NAME,
        options=config_flags(VOLUMETRIC, skip=("threads", "script", "mesh", "out")),
        script=stage_script("volumetric_pose"),
        code=stage_code("volumetric_pose"),
    threads: VOLUMETRIC["threads"]
    log: log_file("volumetric_pose", "", VOLUMETRIC_AUTHORED)
    benchmark: benchmark_file("volumetric_pose", "", VOLUMETRIC_AUTHORED)
    conda: "../envs/posefix.yaml"
    shell:
        "python {params.script:q} --mesh {input.mesh:q} --script {input.script:q} --out {output.library:q}"
        " --artifact {output.artifact:q} --name {params.name:q} {params.options} --threads {threads} --log {log:q}"


ANIMATE = config["volumetric"]["animate"]
ANIMATE_TRACKS = ANIMATE["tracks"] or str(Path(workflow.basedir) / "examples" / "demo-limb-markers.csv")
ANIMATE_MESH = ANIMATE["mesh"] or f"{config['demo']['folder']}/{demo.REFERENCE_NAME}{demo.REFERENCE_SUFFIX}"
ANIMATE_NAME = Path(ANIMATE_TRACKS).name.split(".")[0]
ANIMATED = f"{config['results']}/authored/{ANIMATE_NAME}"


rule volumetric_animate:
    input:
        mesh=ANIMATE_MESH,
        tracks=ANIMATE_TRACKS,
    output:
        library=directory(f"{ANIMATE['out']}/{ANIMATE_NAME}"),
        artifact=f"{ANIMATED}/volumetric_animate.h5",
    params:
        name=ANIMATE_NAME,
        options=config_flags(ANIMATE, skip=("threads", "tracks", "mesh", "out", "rigid")),
        rigid=" ".join(f"--rigid {shlex.quote(name + '=' + ','.join(str(float(v)) for c in box for v in c))}"
                       for name, box in ANIMATE["rigid"].items()),
        script=stage_script("volumetric_animate"),
        code=stage_code("volumetric_animate"),
    threads: ANIMATE["threads"]
    log: log_file("volumetric_animate", "", ANIMATED)
    benchmark: benchmark_file("volumetric_animate", "", ANIMATED)
    conda: "../envs/posefix.yaml"
    shell:
        "python {params.script:q} --mesh {input.mesh:q} --tracks {input.tracks:q} --out {output.library:q}"
        " --artifact {output.artifact:q} --name {params.name:q} {params.options} {params.rigid}"
        " --threads {threads} --log {log:q}"


rule author_volumetric:  # its name before 2026-12 (common.smk: RENAMED_RULES)
    input:
        rules.volumetric_pose.output,


rule animate_volumetric:  # its name before 2026-12 (common.smk: RENAMED_RULES)
    input:
        rules.volumetric_animate.output,
