# The pose library: the built-in demo (only without --config library=...), the validation of the
# reference once and of every pose on its own (adding or fixing a pose reruns only that pose).

rule demo:
    output:
        library_files() if IS_DEMO else [],
    params:
        folder=lambda wildcards, output: os.path.dirname(output[0]),
        options=config_flags(config["demo"], skip=("folder",)),
        script=stage_script("demo"),
        code=stage_code("demo"),
    threads: 1
    resources: mem_mb=memory_mb("demo")
    log: log_file("demo", None)
    benchmark: benchmark_file("demo", None)
    conda: "../envs/posefix.yaml"
    shell:
        "python {params.script:q} --out {params.folder:q} {params.options}"
        " --log {log:q}"


rule validate_reference:
    input:
        LIBRARY.reference.path,
    output:
        f"{RESULTS}/reference.h5",
    params:
        folder=lambda wildcards, input: os.path.dirname(input[0]),
        reference=LIBRARY.reference.name,
        name=LIBRARY.name,
        script=stage_script("validate"),
        code=stage_code("validate"),
    threads: 1
    resources: mem_mb=memory_mb("validate_reference")
    log: log_file("validate_reference", None)
    benchmark: benchmark_file("validate_reference", None)
    conda: "../envs/posefix.yaml"
    shell:
        "python {params.script:q} --library {params.folder:q} --reference {params.reference:q}"
        " --reference-only --name {params.name:q} --out {output:q} --log {log:q}"


rule validate:
    input:
        reference=LIBRARY.reference.path,
        target=pose_file,
        checked=rules.validate_reference.output[0],
    output:
        f"{RESULTS}/{{pose}}/validate.h5",
    params:
        folder=lambda wildcards, input: os.path.dirname(input[0]),
        reference=LIBRARY.reference.name,
        name=LIBRARY.name,
        script=stage_script("validate"),
        code=stage_code("validate"),
    threads: 1
    resources: mem_mb=memory_mb("validate")
    log: log_file("validate")
    benchmark: benchmark_file("validate")
    conda: "../envs/posefix.yaml"
    shell:
        "python {params.script:q} --library {params.folder:q} --reference {params.reference:q}"
        " --poses {wildcards.pose:q} --name {params.name:q} --out {output:q} --log {log:q}"
