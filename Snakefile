# posefix: repair self-intersections in a pose library by space-time integration (S0).
# Data flow, one pose at a time after the library is validated:
#   demo (only without --config library=...) -> validate -> keyframes -> classify -> constraints
#   -> fit -> integrate -> verify -> export (the repaired mesh), render (report figures) and
#   downstream (Gauss-Newton check of original vs repaired pose, S0 §5, with its figure);
#   then summary and overview over all poses. `snakemake --report reports/<library>/report.html`
#   collects the report() outputs (captions in rules/captions/).
# Rules only wire stage scripts (stages/<rule>.py); the math is in lib/posefix/.
from snakemake.utils import min_version

min_version("9.0")


configfile: os.path.join(workflow.basedir, "config.yaml")


include: "rules/common.smk"


report: "rules/captions/workflow.rst"


wildcard_constraints:
    pose="|".join(re.escape(p) for p in POSES),


localrules:
    all,
    summary,
    overview,


rule all:
    input:
        [repaired_file(p) for p in POSES],
        expand(f"{REPORTS}/figures/{{pose}}/{{figure}}.png", pose=POSES, figure=FIGURES),
        expand(f"{REPORTS}/figures/{{pose}}/downstream.png", pose=POSES),
        f"{REPORTS}/summary.json",
        f"{REPORTS}/overview.png",


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


rule keyframes:
    input:
        library=rules.validate.output[0],
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
    threads: config["fit"]["threads"]
    resources:
        mem_mb=int(1000 * config["fit"]["memory_gb"]) + 1000,
    log:
        f"{RESULTS}/logs/{{pose}}/fit.log",
    benchmark:
        f"{RESULTS}/benchmarks/{{pose}}/fit.tsv"
    shell:
        "{params.python:q} {params.script:q} --constraints {input:q} {params.options}"
        " --checkpoint {params.checkpoint:q} --threads {threads} --out {output:q} --log {log:q}"


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
    threads: config["integrate"]["threads"]
    log:
        f"{RESULTS}/logs/{{pose}}/integrate.log",
    benchmark:
        f"{RESULTS}/benchmarks/{{pose}}/integrate.tsv"
    shell:
        "{params.python:q} {params.script:q} --fit {input.fit:q} --constraints {input.constraints:q}"
        " --keyframes {input.keyframes:q} --device {params.device} --rtol {params.rtol} --atol-rel {params.atol}"
        " --h0 {params.h0} --vec {params.vec} --threads {threads} --out {output:q} --log {log:q}"


rule verify:
    input:
        keyframes=rules.keyframes.output[0],
        classify=rules.classify.output[0],
        integrate=rules.integrate.output[0],
        fit=rules.fit.output[0],
    output:
        f"{RESULTS}/{{pose}}/verify.h5",
    params:
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
    threads: config["verify"]["threads"]
    log:
        f"{RESULTS}/logs/{{pose}}/verify.log",
    benchmark:
        f"{RESULTS}/benchmarks/{{pose}}/verify.tsv"
    shell:
        "{params.python:q} {params.script:q} --keyframes {input.keyframes:q} --classify {input.classify:q}"
        " --integrate {input.integrate:q} --fit {input.fit:q} --fallback-eps {params.fallback}"
        " --fallback-fit {params.fallback_fit}"
        " --ring {params.ring} --max-rings {params.rings} {params.switches}"
        " --threads {threads} --out {output:q} --log {log:q}"


rule export:
    input:
        verify=rules.verify.output[0],
        target=pose_file,
    output:
        f"{RESULTS}/repaired/{{pose}}{{suffix}}",
    wildcard_constraints:
        suffix=r"\.(obj|ply|off)(\.gz)?",
    params:
        python=PYTHON,
        script=stage_script("export"),
    threads: 1
    log:
        f"{RESULTS}/logs/{{pose}}/export{{suffix}}.log",
    benchmark:
        f"{RESULTS}/benchmarks/{{pose}}/export{{suffix}}.tsv"
    shell:
        "{params.python:q} {params.script:q} --verify {input.verify:q} --target {input.target:q}"
        " --out {output:q} --log {log:q}"


rule downstream:
    input:
        keyframes=rules.keyframes.output[0],
        verify=rules.verify.output[0],
    output:
        h5=f"{RESULTS}/{{pose}}/downstream.h5",
        png=report(
            f"{REPORTS}/figures/{{pose}}/downstream.png",
            caption="rules/captions/downstream.rst",
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
        python=PYTHON,
        script=stage_script("downstream"),
    threads: config["downstream"]["threads"]
    log:
        f"{RESULTS}/logs/{{pose}}/downstream.log",
    benchmark:
        f"{RESULTS}/benchmarks/{{pose}}/downstream.tsv"
    shell:
        "{params.python:q} {params.script:q} --keyframes {input.keyframes:q} --verify {input.verify:q}"
        " --alphas {params.alphas} --k-bend {params.k_bend} --k-stretch {params.k_stretch}"
        " --max-iters {params.max_iters} --rel-tol {params.rel_tol} --stall-iters {params.stall_iters}"
        " --threads {threads} --out {output.h5:q} --png {output.png:q} --pose {wildcards.pose:q} --log {log:q}"


rule summary:
    input:
        verify=expand(f"{RESULTS}/{{pose}}/verify.h5", pose=POSES),
        downstream=expand(f"{RESULTS}/{{pose}}/downstream.h5", pose=POSES),
        meshes=[repaired_file(p) for p in POSES],
    output:
        json=f"{REPORTS}/summary.json",
        md=f"{REPORTS}/summary.md",
    params:
        results=lambda wildcards, input: os.path.dirname(os.path.dirname(input.verify[0])),
        poses=",".join(POSES),
        python=PYTHON,
        script=stage_script("summary"),
    threads: 1
    log:
        f"{RESULTS}/logs/summary.log",
    shell:
        "{params.python:q} {params.script:q} --results {params.results:q} --poses {params.poses:q}"
        " --out {output.json:q} --markdown {output.md:q} --log {log:q}"


rule render:
    input:
        keyframes=rules.keyframes.output[0],
        classify=rules.classify.output[0],
        fit=rules.fit.output[0],
        verify=rules.verify.output[0],
        benchmarks=[f"{RESULTS}/benchmarks/{{pose}}/{stage}.tsv" for stage in TIMED_STAGES],
    output:
        [pose_figure(figure) for figure in FIGURES],
    params:
        folder=lambda wildcards, output: os.path.dirname(output[0]),
        benchmarks=lambda wildcards, input: os.path.dirname(input.benchmarks[0]),
        python=PYTHON,
        script=stage_script("render"),
    threads: 1
    log:
        f"{RESULTS}/logs/{{pose}}/render.log",
    benchmark:
        f"{RESULTS}/benchmarks/{{pose}}/render.tsv"
    shell:
        "{params.python:q} {params.script:q} --keyframes {input.keyframes:q} --classify {input.classify:q}"
        " --fit {input.fit:q} --verify {input.verify:q} --benchmarks {params.benchmarks:q}"
        " --pose {wildcards.pose:q} --out {params.folder:q} --log {log:q}"


rule overview:
    input:
        rules.summary.output.json,
    output:
        png=report(
            f"{REPORTS}/overview.png",
            caption="rules/captions/overview.rst",
            category="1. Library",
            labels={"figure": "all poses at a glance"},
        ),
        html=report(
            f"{REPORTS}/summary.html",
            caption="rules/captions/summary.rst",
            category="1. Library",
            labels={"figure": "summary table"},
        ),
    params:
        python=PYTHON,
        script=stage_script("overview"),
    threads: 1
    log:
        f"{RESULTS}/logs/overview.log",
    shell:
        "{params.python:q} {params.script:q} --summary {input:q} --png {output.png:q} --html {output.html:q}"
        " --log {log:q}"
