# The pose library: the built-in demo (only without --config library=...) and the validation of
# every file before any pose is processed.

rule demo:
    output:
        library_files() if IS_DEMO else [],
    params:
        folder=lambda wildcards, output: os.path.dirname(output[0]),
        seed=config["demo"]["seed"],
        around=config["demo"]["around"],
        python=PYTHON,
        script=stage_script("demo"),
    threads: 1
    log:
        f"{RESULTS}/logs/demo.log",
    benchmark:
        f"{RESULTS}/benchmarks/demo.tsv"
    shell:
        "{params.python:q} {params.script:q} --out {params.folder:q} --seed {params.seed}"
        " --around {params.around} --log {log:q}"


rule validate:
    input:
        library_files(),
    output:
        f"{RESULTS}/library.h5",
    params:
        folder=lambda wildcards, input: os.path.dirname(input[0]),
        reference=LIBRARY.reference.name,
        poses=",".join(POSES),
        name=LIBRARY.name,
        python=PYTHON,
        script=stage_script("validate"),
    threads: 1
    log:
        f"{RESULTS}/logs/validate.log",
    benchmark:
        f"{RESULTS}/benchmarks/validate.tsv"
    shell:
        "{params.python:q} {params.script:q} --library {params.folder:q} --reference {params.reference:q}"
        " --poses {params.poses:q} --name {params.name:q} --out {output:q} --log {log:q}"
