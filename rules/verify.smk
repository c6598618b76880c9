# Per pose: verification and repair of the integrated pose (posefix.verify), and the repaired meshes (space-time's
# and the other repairs') in the target's format.

rule verify:
    input:
        keyframes=rules.keyframes.output[0],
        classify=rules.classify.output[0],
        integrate=rules.integrate.output[0],
        fit=rules.fit.output[0],
    output:
        f"{RESULTS}/{{pose}}/verify.h5",
    params:
        options=config_flags(config["verify"]),
        contact=config_flags(config["contact"], skip=("repair",)),
        script=stage_script("verify"),
        code=stage_code("verify"),
    threads: config["verify"]["threads"]
    resources: mem_mb=memory_mb("verify")
    log: log_file("verify")
    benchmark: benchmark_file("verify")
    conda: "../envs/posefix.yaml"
    shell:
        "python {params.script:q} --keyframes {input.keyframes:q} --classify {input.classify:q}"
        " --integrate {input.integrate:q} --fit {input.fit:q} {params.options} {params.contact}"
        " --threads {threads} --out {output:q} --log {log:q}"


rule export:
    input:
        verify=rules.verify.output[0],
        reference=LIBRARY.reference.path,
        target=pose_file,
    output:
        f"{RESULTS}/repaired/{{pose}}{{suffix}}",
    wildcard_constraints:
        suffix=r"\.(obj|ply|off)(\.gz)?",
    params:
        script=stage_script("export"),
        code=stage_code("export"),
    threads: 1
    resources: mem_mb=memory_mb("export")
    log: log_file("export{suffix}")
    benchmark: benchmark_file("export{suffix}")
    conda: "../envs/posefix.yaml"
    shell:
        "python {params.script:q} --artifact {input.verify:q} --reference {input.reference:q}"
        " --target {input.target:q}"
        " --out {output:q} --log {log:q}"


rule export_repair:
    input:
        artifact=f"{RESULTS}/{{pose}}/{{repair}}.h5",
        reference=LIBRARY.reference.path,
        target=pose_file,
    output:
        f"{RESULTS}/repaired-{{repair}}/{{pose}}{{suffix}}",
    wildcard_constraints:
        repair="|".join(REPAIR_CHOICES),
        suffix=r"\.(obj|ply|off)(\.gz)?",
    params:
        script=stage_script("export"),
        code=stage_code("export"),
    threads: 1
    resources: mem_mb=memory_mb("export_repair")
    log: log_file("export_{repair}{suffix}")
    benchmark: benchmark_file("export_{repair}{suffix}")
    conda: "../envs/posefix.yaml"
    shell:
        "python {params.script:q} --artifact {input.artifact:q} --stage repair_{wildcards.repair}"
        " --reference {input.reference:q} --target {input.target:q} --out {output:q} --log {log:q}"
