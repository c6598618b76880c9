# The contact repair: per pose, the reference carried through the key frames by the IPC contact solver
# (posefix.contact.keyframe_tracking; the solver's settings: config contact, the rule's: contact.repair), compared
# beside space-time when config `repairs` names it: the yardstick of the space-time repair's contact finish.


rule repair_contact:
    input:
        keyframes=rules.keyframes.output[0],
        classify=rules.classify.output[0],
    output:
        f"{RESULTS}/{{pose}}/contact.h5",
    params:
        options=config_flags(config["contact"], skip=("repair",)),
        script=stage_script("repair_contact"),
        code=stage_code("repair_contact"),
    threads: config["contact"]["repair"]["threads"]
    resources: mem_mb=memory_mb("repair_contact")
    log: log_file("repair_contact")
    benchmark: benchmark_file("repair_contact")
    conda: "../envs/posefix.yaml"
    shell:
        "python {params.script:q} --keyframes {input.keyframes:q} --classify {input.classify:q}"
        " --out {output:q} {params.options} --threads {threads} --log {log:q}"
