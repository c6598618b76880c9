# Per pose: the downstream Gauss-Newton discrete-shell check (S0 §5, posefix.check), parallel to
# export and render, so it adds no level to the per-pose chain. With downstream.baselines, also
# towards the baseline repairs' poses (config baselines).
CHECK_BASELINES = config["downstream"]["baselines"]


rule downstream:
    input:
        keyframes=rules.keyframes.output[0],
        verify=rules.verify.output[0],
        baselines=lambda wildcards: (
            list(baseline_artifacts(wildcards.pose).values()) if CHECK_BASELINES else []
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
        alphas=",".join(map(str, config["downstream"]["alphas"])),
        k_bend=",".join(map(str, config["downstream"]["k_bend"])),
        k_stretch=config["downstream"]["k_stretch"],
        max_iters=config["downstream"]["max_iters"],
        rel_tol=config["downstream"]["rel_tol"],
        stall_iters=config["downstream"]["stall_iters"],
        baselines=lambda wildcards: (
            named_options("--baseline", baseline_artifacts(wildcards.pose)) if CHECK_BASELINES else ""
        ),
        python=PYTHON,
        script=stage_script("downstream"),
        code=stage_code("downstream"),
    threads: config["downstream"]["threads"]
    log:
        f"{RESULTS}/logs/{{pose}}/downstream.log",
    benchmark:
        f"{RESULTS}/benchmarks/{{pose}}/downstream.tsv"
    shell:
        "{params.python:q} {params.script:q} --keyframes {input.keyframes:q} --verify {input.verify:q}"
        " --alphas {params.alphas} --k-bend {params.k_bend} --k-stretch {params.k_stretch}"
        " --max-iters {params.max_iters} --rel-tol {params.rel_tol} --stall-iters {params.stall_iters}"
        " {params.baselines} --threads {threads} --out {output.h5:q} --png {output.png:q} --pose {wildcards.pose:q}"
        " --log {log:q}"
