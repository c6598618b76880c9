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
        frames=config["keyframes"]["count"],
        switches=" ".join(
            [
                flag(config["keyframes"]["align"], "--no-align"),
                flag(config["keyframes"]["unwrap"], "--no-unwrap"),
            ]
        ),
        python=PYTHON,
        script=stage_script("keyframes"),
        code=stage_code("keyframes"),
    threads: config["keyframes"]["threads"]
    log:
        f"{RESULTS}/logs/{{pose}}/keyframes.log",
    benchmark:
        f"{RESULTS}/benchmarks/{{pose}}/keyframes.tsv"
    shell:
        "{params.python:q} {params.script:q} --reference {input.reference:q} --target {input.target:q}"
        " --count {params.frames} {params.switches} --threads {threads} --out {output:q} --log {log:q}"


rule classify:
    input:
        keyframes=rules.keyframes.output[0],
        exclude=exclude_files,
    output:
        f"{RESULTS}/{{pose}}/classify.h5",
    params:
        ring=config["classify"]["ring"],
        contact=config["classify"]["contact"],
        radius=config["classify"]["contact_radius"],
        exclude=exclude_args,
        python=PYTHON,
        script=stage_script("classify"),
        code=stage_code("classify"),
    threads: config["classify"]["threads"]
    log:
        f"{RESULTS}/logs/{{pose}}/classify.log",
    benchmark:
        f"{RESULTS}/benchmarks/{{pose}}/classify.tsv"
    shell:
        "{params.python:q} {params.script:q} --keyframes {input.keyframes:q} --ring {params.ring}"
        " --contact {params.contact} --contact-radius {params.radius} {params.exclude}"
        " --threads {threads} --out {output:q} --log {log:q}"


rule constraints:
    input:
        keyframes=rules.keyframes.output[0],
        classify=rules.classify.output[0],
    output:
        f"{RESULTS}/{{pose}}/constraints.h5",
    params:
        samples=config["constraints"]["samples"],
        tau=config["constraints"]["tau"],
        tangents=config["constraints"]["tangents"],
        python=PYTHON,
        script=stage_script("constraints"),
        code=stage_code("constraints"),
    threads: config["constraints"]["threads"]
    log:
        f"{RESULTS}/logs/{{pose}}/constraints.log",
    benchmark:
        f"{RESULTS}/benchmarks/{{pose}}/constraints.tsv"
    shell:
        "{params.python:q} {params.script:q} --keyframes {input.keyframes:q} --classify {input.classify:q}"
        " --samples {params.samples} --tau {params.tau} --tangents {params.tangents}"
        " --threads {threads} --out {output:q} --log {log:q}"


rule fit:
    input:
        rules.constraints.output[0],
    output:
        f"{RESULTS}/{{pose}}/fit.h5",
    params:
        options=fit_options,
        checkpoint=lambda wildcards, output: output[0].replace(".h5", ".checkpoint"),
        python=PYTHON,
        script=stage_script("fit"),
        code=stage_code("fit"),
    threads: config["fit"]["threads"]
    resources:
        mem_mb=int(1000 * config["fit"]["memory_gb"]) + 2000,
    log:
        f"{RESULTS}/logs/{{pose}}/fit.log",
    benchmark:
        f"{RESULTS}/benchmarks/{{pose}}/fit.tsv"
    shell:
        "{params.python:q} {params.script:q} --constraints {input:q} {params.options}"
        " --checkpoint {params.checkpoint:q} --threads {threads} --mem-mb {resources.mem_mb}"
        " --out {output:q} --log {log:q}"


rule integrate:
    input:
        fit=rules.fit.output[0],
        constraints=rules.constraints.output[0],
        keyframes=rules.keyframes.output[0],
    output:
        f"{RESULTS}/{{pose}}/integrate.h5",
    params:
        device=config["integrate"]["device"],
        rtol=config["integrate"]["rtol"],
        atol=config["integrate"]["atol_rel"],
        h0=config["integrate"]["h0"],
        vec=config["integrate"]["vec"],
        python=PYTHON,
        script=stage_script("integrate"),
        code=stage_code("integrate"),
    threads: config["integrate"]["threads"]
    log:
        f"{RESULTS}/logs/{{pose}}/integrate.log",
    benchmark:
        f"{RESULTS}/benchmarks/{{pose}}/integrate.tsv"
    shell:
        "{params.python:q} {params.script:q} --fit {input.fit:q} --constraints {input.constraints:q}"
        " --keyframes {input.keyframes:q} --device {params.device} --rtol {params.rtol} --atol-rel {params.atol}"
        " --h0 {params.h0} --vec {params.vec} --threads {threads} --out {output:q} --log {log:q}"
