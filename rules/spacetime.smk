# S0, per pose: key frames -> classification (V_C) -> space-time constraints -> RBF fit -> RK45
# integration of every reference vertex (posefix.spacetime).

rule keyframes:
    input:
        checked=rules.validate.output[0],
        reference=LIBRARY.reference.path,
        target=pose_file,
    output:
        f"{RESULTS}/{{pose}}/keyframes.h5",
    params:
        options=config_flags(config["keyframes"]),
        script=stage_script("keyframes"),
        code=stage_code("keyframes"),
    threads: config["keyframes"]["threads"]
    resources: mem_mb=memory_mb("keyframes")
    log: log_file("keyframes")
    benchmark: benchmark_file("keyframes")
    conda: "../envs/posefix.yaml"
    shell:
        "python {params.script:q} --reference {input.reference:q} --target {input.target:q}"
        " {params.options} --threads {threads} --out {output:q} --log {log:q}"


rule classify:
    input:
        keyframes=rules.keyframes.output[0],
        exclude=exclude_files,
    output:
        f"{RESULTS}/{{pose}}/classify.h5",
    params:
        options=config_flags(config["classify"], skip=("threads", "exclude")),
        exclude=exclude_args,
        script=stage_script("classify"),
        code=stage_code("classify"),
    threads: config["classify"]["threads"]
    resources: mem_mb=memory_mb("classify")
    log: log_file("classify")
    benchmark: benchmark_file("classify")
    conda: "../envs/posefix.yaml"
    shell:
        "python {params.script:q} --keyframes {input.keyframes:q} {params.options}"
        " {params.exclude}"
        " --threads {threads} --out {output:q} --log {log:q}"


rule constraints:
    input:
        keyframes=rules.keyframes.output[0],
        classify=rules.classify.output[0],
    output:
        intermediate(f"{RESULTS}/{{pose}}/constraints.h5"),
    params:
        options=config_flags(config["constraints"]),
        script=stage_script("constraints"),
        code=stage_code("constraints"),
    threads: config["constraints"]["threads"]
    resources: mem_mb=memory_mb("constraints")
    log: log_file("constraints")
    benchmark: benchmark_file("constraints")
    conda: "../envs/posefix.yaml"
    shell:
        "python {params.script:q} --keyframes {input.keyframes:q} --classify {input.classify:q}"
        " {params.options}"
        " --threads {threads} --out {output:q} --log {log:q}"


rule fit:
    input:
        rules.constraints.output[0],
    output:
        f"{RESULTS}/{{pose}}/fit.h5",
    params:
        options=config_flags(config["fit"]),
        checkpoint=lambda wildcards, output: output[0].replace(".h5", ".checkpoint"),
        script=stage_script("fit"),
        code=stage_code("fit"),
    threads: config["fit"]["threads"]
    resources: mem_mb=within_limit(int(1000 * config["fit"]["memory_gb"]) + 2000)
    log: log_file("fit")
    benchmark: benchmark_file("fit")
    conda: "../envs/posefix.yaml"
    shell:
        "python {params.script:q} --constraints {input:q} {params.options}"
        " --checkpoint {params.checkpoint:q} --threads {threads} --mem-mb {resources.mem_mb}"
        " --out {output:q} --log {log:q}"


rule integrate:
    input:
        fit=rules.fit.output[0],
        keyframes=rules.keyframes.output[0],
    output:
        intermediate(f"{RESULTS}/{{pose}}/integrate.h5"),
    params:
        options=config_flags(config["integrate"]),
        script=stage_script("integrate"),
        code=stage_code("integrate"),
    threads: config["integrate"]["threads"]
    resources: mem_mb=memory_mb("integrate")
    log: log_file("integrate")
    benchmark: benchmark_file("integrate")
    conda: "../envs/posefix.yaml"
    shell:
        "python {params.script:q} --fit {input.fit:q}"
        " --keyframes {input.keyframes:q} {params.options} --threads {threads} --out {output:q} --log {log:q}"
