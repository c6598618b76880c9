# Per pose: the downstream Gauss-Newton discrete-shell check (S0 §5, posefix.downstream), parallel to
# export and render, so it adds no level to the per-pose chain. With downstream.repairs, also
# towards the other repairs' poses (config repairs).
CHECK_REPAIRS = config["downstream"]["repairs"]


rule downstream:
    input:
        keyframes=rules.keyframes.output[0],
        verify=rules.verify.output[0],
        repairs=lambda wildcards: (
            list(repair_artifacts(wildcards.pose).values()) if CHECK_REPAIRS else []
        ),
    output:
        h5=f"{RESULTS}/{{pose}}/downstream.h5",
        png=report(
            f"{REPORTS}/figures/{{pose}}/downstream.png",
            caption="captions/downstream.rst",
            category="2. Poses",
            subcategory="{pose}",
            labels={"pose": "{pose}", "figure": "Gauss-Newton check"},
        ),
    params:
        options=config_flags(config["downstream"], skip=("threads", "repairs")),
        repairs=lambda wildcards: (
            named_options("--repair", repair_artifacts(wildcards.pose)) if CHECK_REPAIRS else ""
        ),
        script=stage_script("downstream"),
        code=stage_code("downstream"),
    threads: config["downstream"]["threads"]
    resources: mem_mb=memory_mb("downstream")
    log: log_file("downstream")
    benchmark: benchmark_file("downstream")
    conda: "../envs/posefix.yaml"
    shell:
        "python {params.script:q} --keyframes {input.keyframes:q} --verify {input.verify:q}"
        " {params.options} {params.repairs} --threads {threads} --out {output.h5:q} --png {output.png:q} --pose {wildcards.pose:q}"
        " --log {log:q}"
