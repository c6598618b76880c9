"""The workflow's plumbing: the stage command line and logging, the ``posefix`` command, config checks and the
generated configuration page, Snakemake lock clearing, code fingerprints, resource budgets, timings, the
built-in demo library, and where the workflow's files are (the wheel's ``posefix/_workflow/`` or the checkout)."""
