"""Repair flags: defined once, documented from there, counted per kind."""

import numpy as np

from conftest import ROOT
from posefix.verify.flags import (FLAGS, PUSHED, REPLACED_NEW_INTERSECTION, REPLACED_PASS_THROUGH, REPRODUCED,
                                  SEPARATED, SMOOTHED, describe_flags, flag_counts)


def test_flags_are_distinct_bits_in_order():
    bits = [f.bit for f in FLAGS]
    assert bits == sorted(bits) == [1 << k for k in range(len(bits))]
    assert len({f.label for f in FLAGS}) == len(FLAGS)


def test_artifact_docs_give_the_flags_meanings_from_the_library():
    text = (ROOT / "docs" / "artifacts.md").read_text()
    row = next(line for line in text.splitlines() if line.startswith("| `replaced` |"))
    assert describe_flags() in row
    assert describe_flags().startswith("1 target (") and f"{SEPARATED} separated (" in describe_flags()


def test_flag_counts_by_kind():
    F = np.array([[0, 1, 2], [2, 3, 4], [4, 5, 6]])
    replaced = np.array([REPLACED_PASS_THROUGH, REPRODUCED, REPRODUCED | PUSHED, SMOOTHED, SEPARATED | REPRODUCED,
                         REPLACED_NEW_INTERSECTION, 0], dtype=np.uint8)
    new = np.array([True, False, True])
    c = flag_counts(replaced, new, F)
    assert c == {"fallback_vertices": 4, "fallback_pass_through": 1, "fallback_new_intersection": 3,
                 "reproduced_vertices": 3, "pushed_vertices": 1, "repaired_new_in_fallback": 1}
