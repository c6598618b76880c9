"""Hand-written prose of the benchmark pages, kept in benchmarks/notes.md and woven into the generated pages.

`make bench` regenerates every page of reports/bench/ from its measurements; what a person wrote about them (which
repair wins where and why, the tables of a run before a change, the code a page was measured at) lives in
``notes.md`` beside this module, one block per place::

    <!-- BENCHMARKS.md | after | ## Repairs compared: ... -->    right after that heading
    <!-- BENCHMARKS.md | end | ## Repairs compared: ... -->      at the end of that heading's section
    <!-- memory.md | end | -->                                    at the end of the page

A block whose heading the page no longer has goes to the end of the page under :data:`ORPHANS`, with a warning:
a renamed section loses no prose.
"""

import logging
from pathlib import Path

log = logging.getLogger("posefix.benchmarks")

NOTES = Path(__file__).with_name("notes.md")
ORPHANS = "## Notes whose section is gone"
"""The heading at the end of a page under which the notes go whose heading the page no longer has."""


def read_notes(path=NOTES):
    """The blocks of the notes file ``path``: list of (page, where, heading, text), text without its surrounding
    blank lines."""
    blocks = []
    for line in Path(path).read_text().splitlines():
        if line.startswith("<!--") and line.endswith("-->") and line.count("|") == 2:
            page, where, heading = (part.strip() for part in line[4:-3].split("|"))
            blocks.append((page, where, heading, []))
        elif blocks:
            blocks[-1][3].append(line)
    return [(page, where, heading, "\n".join(lines).strip("\n")) for page, where, heading, lines in blocks]


def with_notes(text, page, notes=None):
    """The generated page ``text`` (str) named ``page`` (e.g. "BENCHMARKS.md") with its notes (:func:`read_notes`
    by default) in place, each followed by a blank line; one block per page, place and heading.

    Examples
    --------
    >>> page = "# Page\\n\\n## A\\n\\ntable A\\n\\n### A.1\\n\\nmore A\\n\\n## B\\n\\ntable B\\n"
    >>> notes = [("p.md", "after", "## A", "Why A wins."), ("p.md", "end", "## A", "An older run of A."),
    ...          ("p.md", "end", "", "Measured at abc1234.")]
    >>> print(with_notes(page, "p.md", notes), end="")
    # Page
    <BLANKLINE>
    ## A
    <BLANKLINE>
    Why A wins.
    <BLANKLINE>
    table A
    <BLANKLINE>
    ### A.1
    <BLANKLINE>
    more A
    <BLANKLINE>
    An older run of A.
    <BLANKLINE>
    ## B
    <BLANKLINE>
    table B
    <BLANKLINE>
    Measured at abc1234.
    """
    lines = text.splitlines()
    for _, where, heading, note in [b for b in (read_notes() if notes is None else notes) if b[0] == page]:
        if heading and heading not in lines:
            log.warning("benchmarks/notes.md: %s has no heading %r any more: its note goes under %r", page,
                        heading, ORPHANS)
            if ORPHANS not in lines:
                lines += ["", ORPHANS, ""]
            where, heading, note = "end", "", f"*Formerly under “{heading.lstrip('#').strip()}”:*\n\n{note}"
        at = _place(lines, where, heading)
        lines[at:at] = note.splitlines() + [""]
    return "\n".join(lines).rstrip("\n") + "\n"


def _place(lines, where, heading):
    """The index in ``lines`` (list of str, changed: trailing blank lines dropped for the end of the page) where a
    note goes: after ``heading`` and its blank line, or at the end of its section (before the next heading of its
    level or above; the end of the page for an empty heading)."""
    if not heading:
        while lines and not lines[-1].strip():
            lines.pop()
        lines.append("")
        return len(lines)
    start = lines.index(heading) + 1
    if where == "after":
        return start + 1 if start < len(lines) and not lines[start].strip() else start
    level = len(heading) - len(heading.lstrip("#"))
    return next((i for i in range(start, len(lines)) if lines[i].startswith("#")
                 and len(lines[i]) - len(lines[i].lstrip("#")) <= level), len(lines))
