# Reports: the summary of a library, the figures per pose, the overview and the 3D viewer (posefix.report), S0
# compared with the other repairs of config repairs. Captions of the report() outputs are in
# rules/captions/.

rule summary:
    input:
        verify=expand(f"{RESULTS}/{{pose}}/verify.h5", pose=POSES),
        downstream=expand(f"{RESULTS}/{{pose}}/downstream.h5", pose=POSES),
        classify=expand(f"{RESULTS}/{{pose}}/classify.h5", pose=POSES),  # V_C of the other repairs' deviations
        keyframes=expand(f"{RESULTS}/{{pose}}/keyframes.h5", pose=POSES),  # reference and target: distortion
        repairs=[path for p in POSES for path in repair_artifacts(p).values()],
        meshes=[repaired_file(p) for p in POSES],
    output:
        json=f"{REPORTS}/summary.json",
        md=f"{REPORTS}/summary.md",
    params:
        results=lambda wildcards, input: os.path.dirname(os.path.dirname(input.verify[0])),
        poses=",".join(SUMMARY_POSES),  # with the poses an earlier run finished
        repairs=f"--repairs {','.join(REPAIRS)}" if REPAIRS else "",
        limit=config["summary"]["distortion_limit"],
        script=stage_script("summary"),
        code=stage_code("summary"),
    threads: 1
    resources: mem_mb=memory_mb("summary")
    log: log_file("summary", None)
    conda: "../envs/posefix.yaml"
    shell:
        "python {params.script:q} --results {params.results:q} --poses {params.poses:q}"
        " {params.repairs} --distortion-limit {params.limit} --out {output.json:q} --markdown {output.md:q}"
        " --log {log:q}"


rule render:
    input:
        keyframes=rules.keyframes.output[0],
        classify=rules.classify.output[0],
        fit=rules.fit.output[0],
        verify=rules.verify.output[0],
        benchmarks=[f"{RESULTS}/benchmarks/{{pose}}/{stage}.tsv" for stage in TIMED_STAGES],
        repairs=lambda wildcards: list(repair_artifacts(wildcards.pose).values()),
    output:
        [pose_figure(figure) for figure in POSE_FIGURES],
    params:
        folder=lambda wildcards, output: os.path.dirname(output[0]),
        benchmarks=lambda wildcards, input: os.path.dirname(input.benchmarks[0]),
        repairs=lambda wildcards: named_options("--repair", repair_artifacts(wildcards.pose)),
        limit=config["summary"]["distortion_limit"],
        script=stage_script("render"),
        code=stage_code("render"),
    threads: 1
    resources: mem_mb=memory_mb("render")
    log: log_file("render")
    benchmark: benchmark_file("render")
    conda: "../envs/posefix.yaml"
    shell:
        "python {params.script:q} --keyframes {input.keyframes:q} --classify {input.classify:q}"
        " --fit {input.fit:q} --verify {input.verify:q} --benchmarks {params.benchmarks:q}"
        " {params.repairs} --distortion-limit {params.limit} --pose {wildcards.pose:q} --out {params.folder:q}"
        " --log {log:q}"


rule overview:
    input:
        rules.summary.output.json,
    output:
        png=report(
            f"{REPORTS}/overview.png",
            caption="captions/overview.rst",
            category="1. Library",
            labels={"figure": "all poses at a glance"},
        ),
        html=report(
            f"{REPORTS}/summary.html",
            caption="captions/summary.rst",
            category="1. Library",
            labels={"figure": "summary table"},
        ),
    params:
        script=stage_script("overview"),
        code=stage_code("overview"),
    threads: 1
    resources: mem_mb=memory_mb("overview")
    log: log_file("overview", None)
    conda: "../envs/posefix.yaml"
    shell:
        "python {params.script:q} --summary {input:q} --png {output.png:q} --html {output.html:q}"
        " --log {log:q}"


rule viewer:
    input:
        summary=rules.summary.output.json,
        keyframes=expand(f"{RESULTS}/{{pose}}/keyframes.h5", pose=POSES),
        classify=expand(f"{RESULTS}/{{pose}}/classify.h5", pose=POSES),
        verify=expand(f"{RESULTS}/{{pose}}/verify.h5", pose=POSES),
        repairs=[path for p in POSES for path in repair_artifacts(p).values()],
        page=VIEWER_PAGE,  # the page's template, script and three.js: a changed page rebuilds it
    output:
        report(
            f"{REPORTS}/viewer.html",
            caption="captions/viewer.rst",
            category="1. Library",
            labels={"figure": "3D viewer"},
        ),
    params:
        results=lambda wildcards, input: os.path.dirname(os.path.dirname(input.verify[0])),
        script=stage_script("viewer"),
        code=stage_code("viewer"),
    threads: 1
    resources: mem_mb=memory_mb("viewer")
    log: log_file("viewer", None)
    conda: "../envs/posefix.yaml"
    shell:
        "python {params.script:q} --summary {input.summary:q} --results {params.results:q} --out {output:q}"
        " --log {log:q}"


onerror:  # the summary of the poses that finished (and a USD or glTF library's files with them), then the failed jobs' posefix error lines (plain snakemake too)
    _errors = failed_job_errors(EVENTS.events, Path.cwd())
    partial_summary(_errors)
    partial_containers()
    print("\n".join(map(recap_line, _errors)), file=sys.stderr)
