# Baseline repairs beside S0, compared in the report (config `baselines`). medial: the reference's
# skeletal mesh once (S1 §2, settings of skeletal_pose), then per pose the medial repair (S1 §4 flow from
# the target, posefix.skeletal.repair). volumetric: the reference's tet mesh once (S4 §2.1), then per pose
# the volumetric fill of the free region (S4's editor, posefix.volumetric.fill). contact: per pose, the
# reference carried through S0's key frames by the IPC contact solver (posefix.contact.keyframe_tracking).
# Every baseline's repaired mesh is exported in the target's format.

MEDIAL = config["repair_medial"]
FILL = config["repair_volumetric"]


rule skeleton:
    input:
        reference=LIBRARY.reference.path,
        checked=rules.validate_reference.output[0],
    output:
        f"{RESULTS}/skeleton.h5",
    params:
        options=config_flags({key: config["skeletal_pose"][key] for key in ("medial", "tol", "smooth_iters",
                                                                             "smooth_step")}),
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
        options=config_flags(MEDIAL),
        script=stage_script("repair_medial"),
        code=stage_code("repair_medial"),
    threads: MEDIAL["threads"]
    resources: mem_mb=memory_mb("repair_medial")
    log: log_file("repair_medial")
    benchmark: benchmark_file("repair_medial")
    conda: "../envs/posefix.yaml"
    shell:
        "python {params.script:q} --reference {input.reference:q} --target {input.target:q}"
        " --skeleton {input.skeleton:q} --out {output:q} {params.options} --threads {threads} --log {log:q}"


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


rule repair_contact:
    input:
        keyframes=rules.keyframes.output[0],
        classify=rules.classify.output[0],
    output:
        f"{RESULTS}/{{pose}}/contact.h5",
    params:
        options=config_flags(config["contact"]),
        script=stage_script("repair_contact"),
        code=stage_code("repair_contact"),
    threads: config["repair_contact"]["threads"]
    resources: mem_mb=memory_mb("repair_contact")
    log: log_file("repair_contact")
    benchmark: benchmark_file("repair_contact")
    conda: "../envs/posefix.yaml"
    shell:
        "python {params.script:q} --keyframes {input.keyframes:q} --classify {input.classify:q}"
        " --out {output:q} {params.options} --threads {threads} --log {log:q}"


rule export_baseline:
    input:
        artifact=f"{RESULTS}/{{pose}}/{{baseline}}.h5",
        reference=LIBRARY.reference.path,
        target=pose_file,
    output:
        f"{RESULTS}/repaired-{{baseline}}/{{pose}}{{suffix}}",
    wildcard_constraints:
        baseline="|".join(BASELINE_CHOICES),
        suffix=r"\.(obj|ply|off)(\.gz)?",
    params:
        script=stage_script("export"),
        code=stage_code("export"),
    threads: 1
    resources: mem_mb=memory_mb("export_baseline")
    log: log_file("export_{baseline}{suffix}")
    benchmark: benchmark_file("export_{baseline}{suffix}")
    conda: "../envs/posefix.yaml"
    shell:
        "python {params.script:q} --artifact {input.artifact:q} --stage repair_{wildcards.baseline}"
        " --reference {input.reference:q} --target {input.target:q} --out {output:q} --log {log:q}"
