# A pose library in one USD or glTF file (config library=character.usd): each pose unpacked into a mesh file under
# results/<library>/poses/ for the stages, and the repaired poses of every repair packed back into the same kind of
# file, results/<library>/repaired[-<repair>]/<file name>. The rules exist only for such a library. A pose is
# unpacked again (and so repaired again) only when its points or the faces change in the file.


if LIBRARY.container:
    MEMBER_DIGESTS = member_digests(LIBRARY.container, LIBRARY.mesh,
                                    cache=Path(".snakemake") / "posefix-containers.json")

    rule unpack:
        input:
            ancient(LIBRARY.container),  # a pose reruns when its points change (params.digest), not the file's time
        output:
            f"{LIBRARY.folder}/{{member}}.ply",
        wildcard_constraints:
            member="|".join(re.escape(p.name) for p in (LIBRARY.reference, *WHOLE_LIBRARY.poses)),
        params:
            container=lambda wildcards: container_flags(),
            reference=lambda wildcards: "--reference" if wildcards.member == LIBRARY.reference.name else "",
            digest=lambda wildcards: MEMBER_DIGESTS[wildcards.member],
            script=stage_script("unpack"),
            code=stage_code("unpack"),
        threads: 1
        resources: mem_mb=memory_mb("unpack")
        log: log_file("unpack", "member")
        benchmark: benchmark_file("unpack", "member")
        conda: "../envs/posefix.yaml"
        shell:
            "python {params.script:q} {params.container} --pose {wildcards.member:q} {params.reference}"
            " --out {output:q} --log {log:q}"


    rule pack:
        input:
            container=LIBRARY.container,
            repaired=lambda wildcards: [f"{RESULTS}/{wildcards.repair}/{p}.ply" for p in SUMMARY_POSES],
        output:
            f"{RESULTS}/{{repair}}/{os.path.basename(LIBRARY.container)}",
        wildcard_constraints:
            repair="repaired(-(" + "|".join(REPAIR_CHOICES) + "))?",
        params:
            container=lambda wildcards: container_flags(),
            folder=lambda wildcards, output: os.path.dirname(output[0]),
            poses=",".join(SUMMARY_POSES),  # this run's and those an earlier run finished
            script=stage_script("pack"),
            code=stage_code("pack"),
        threads: 1
        resources: mem_mb=memory_mb("pack")
        log: log_file("pack-{repair}", None)
        benchmark: benchmark_file("pack-{repair}", None)
        conda: "../envs/posefix.yaml"
        shell:
            "python {params.script:q} {params.container} --repaired {params.folder:q} --poses {params.poses:q}"
            " --out {output:q} --log {log:q}"
