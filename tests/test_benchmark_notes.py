"""Generated stays generated (issue 51): the benchmark pages' hand-written prose lives in benchmarks/notes.md, and
`make bench` weaves it back into the pages it regenerates (benchmarks/notes.py)."""

import importlib.util
import logging

import pytest

from conftest import ROOT


def _notes_module():
    spec = importlib.util.spec_from_file_location("bench_notes", ROOT / "benchmarks" / "notes.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


notes = _notes_module()


@pytest.mark.parametrize("block", notes.read_notes(), ids=lambda b: f"{b[0]} {b[1]} {b[2][:40]}")
def test_every_note_is_in_its_committed_page_under_its_heading(block):
    page, where, heading, text = block
    lines = (ROOT / "reports" / "bench" / page).read_text().splitlines()
    assert where in ("after", "end") and text
    assert not heading or heading in lines, f"{page} has no heading {heading!r}"
    start = lines.index(heading) if heading else 0
    body = "\n".join(lines[start:])
    assert text in body and notes.ORPHANS not in lines


def test_regenerating_a_page_keeps_its_notes_where_they_were():
    """The committed pages with their notes taken out, then put back, are the committed pages byte for byte."""
    for page in sorted({b[0] for b in notes.read_notes()}):
        committed = (ROOT / "reports" / "bench" / page).read_text()
        generated = committed
        for _, _, _, text in (b for b in notes.read_notes() if b[0] == page):
            generated = generated.replace(text + "\n\n", "", 1) if text + "\n\n" in generated \
                else generated.replace("\n" + text + "\n", "\n", 1)
        assert generated != committed and notes.with_notes(generated, page) == committed, page


def test_a_note_whose_heading_is_gone_goes_to_the_end_of_the_page_with_a_warning(caplog):
    page = "# Page\n\n## Renamed\n\ntable\n"
    with caplog.at_level(logging.WARNING, logger="posefix.benchmarks"):
        out = notes.with_notes(page, "p.md", [("p.md", "after", "## Old name", "Why it wins.")])
    assert out == f"# Page\n\n## Renamed\n\ntable\n\n{notes.ORPHANS}\n\n*Formerly under “Old name”:*\n\nWhy it wins.\n"
    assert "## Old name" in caplog.text
