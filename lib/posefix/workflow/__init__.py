"""The workflow's plumbing: the stage command line and logging, the ``posefix`` command, config checks and the
generated configuration page, Snakemake lock clearing, code fingerprints, resource budgets, timings and the
built-in demo library."""
