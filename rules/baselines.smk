# Baseline repairs beside S0, compared in the report (config `baselines`). medial: the reference's
# skeletal mesh once (S1 §2, settings of skeletal_pose), then per pose the medial repair (S1 §4 flow from
# the target, posefix.skeletal.repair) and the repaired mesh in the target's format.

MEDIAL = config["repair_medial"]


rule skeleton:
    input:
        reference=LIBRARY.reference.path,
        library=rules.validate.output[0],
    output:
        f"{RESULTS}/skeleton.h5",
    params:
        options=" ".join(f"--{key.replace('_', '-')} {config['skeletal_pose'][key]}" for key in
                         ("medial", "tol", "smooth_iters", "smooth_step")),
        python=PYTHON,
        script=stage_script("skeleton"),
    threads: 1
    log:
        f"{RESULTS}/logs/skeleton.log",
    benchmark:
        f"{RESULTS}/benchmarks/skeleton.tsv"
    shell:
        "{params.python:q} {params.script:q} --reference {input.reference:q} --out {output:q} {params.options}"
        " --threads {threads} --log {log:q}"


rule repair_medial:
    input:
        reference=LIBRARY.reference.path,
        target=pose_file,
        skeleton=rules.skeleton.output[0],
    output:
        f"{RESULTS}/{{pose}}/medial.h5",
    params:
        options=" ".join(f"--{key.replace('_', '-')} {MEDIAL[key]}" for key in
                         ("margin", "tau", "neighbours", "max_reach", "max_iters")),
        python=PYTHON,
        script=stage_script("repair_medial"),
    threads: MEDIAL["threads"]
    log:
        f"{RESULTS}/logs/{{pose}}/repair_medial.log",
    benchmark:
        f"{RESULTS}/benchmarks/{{pose}}/repair_medial.tsv"
    shell:
        "{params.python:q} {params.script:q} --reference {input.reference:q} --target {input.target:q}"
        " --skeleton {input.skeleton:q} --out {output:q} {params.options} --threads {threads} --log {log:q}"


rule export_medial:
    input:
        medial=rules.repair_medial.output[0],
        target=pose_file,
    output:
        f"{RESULTS}/repaired-medial/{{pose}}{{suffix}}",
    wildcard_constraints:
        suffix=r"\.(obj|ply|off)(\.gz)?",
    params:
        python=PYTHON,
        script=stage_script("export"),
    threads: 1
    log:
        f"{RESULTS}/logs/{{pose}}/export_medial{{suffix}}.log",
    benchmark:
        f"{RESULTS}/benchmarks/{{pose}}/export_medial{{suffix}}.tsv"
    shell:
        "{params.python:q} {params.script:q} --artifact {input.medial:q} --stage repair_medial"
        " --target {input.target:q} --out {output:q} --log {log:q}"
