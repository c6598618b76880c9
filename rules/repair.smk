# Per pose: verification and repair of the integrated pose (posefix.repair), and the repaired mesh
# in the target's format.

rule verify:
    input:
        keyframes=rules.keyframes.output[0],
        classify=rules.classify.output[0],
        integrate=rules.integrate.output[0],
        fit=rules.fit.output[0],
    output:
        f"{RESULTS}/{{pose}}/verify.h5",
    params:
        finish=config["verify"]["finish"],
        free_goal=config["verify"]["free_goal"],
        weight=config["verify"]["constrained_weight"],
        untangle=config["verify"]["untangle_rings"],
        contact=" ".join(
            f"--{key.replace('_', '-')} {value}" for key, value in config["contact"].items()
        ),
        fallback=config["verify"]["fallback_eps"],
        fallback_fit=config["verify"]["fallback_fit"],
        ring=config["verify"]["ring"],
        rings=config["verify"]["max_rings"],
        switches=" ".join(
            [
                flag(config["verify"]["repair_new"], "--no-repair-new"),
                flag(config["verify"]["reproduce"], "--no-reproduce"),
            ]
        ),
        python=PYTHON,
        script=stage_script("verify"),
        code=stage_code("verify"),
    threads: config["verify"]["threads"]
    log:
        f"{RESULTS}/logs/{{pose}}/verify.log",
    benchmark:
        f"{RESULTS}/benchmarks/{{pose}}/verify.tsv"
    shell:
        "{params.python:q} {params.script:q} --keyframes {input.keyframes:q} --classify {input.classify:q}"
        " --integrate {input.integrate:q} --fit {input.fit:q} --finish {params.finish}"
        " --free-goal {params.free_goal} --constrained-weight {params.weight}"
        " --untangle-rings {params.untangle} {params.contact}"
        " --fallback-eps {params.fallback}"
        " --fallback-fit {params.fallback_fit}"
        " --ring {params.ring} --max-rings {params.rings} {params.switches}"
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
        python=PYTHON,
        script=stage_script("export"),
        code=stage_code("export"),
    threads: 1
    log:
        f"{RESULTS}/logs/{{pose}}/export{{suffix}}.log",
    benchmark:
        f"{RESULTS}/benchmarks/{{pose}}/export{{suffix}}.tsv"
    shell:
        "{params.python:q} {params.script:q} --artifact {input.verify:q} --reference {input.reference:q}"
        " --target {input.target:q}"
        " --out {output:q} --log {log:q}"
