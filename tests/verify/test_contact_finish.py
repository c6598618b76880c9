"""The contact finish of stage verify: V_C on its targets, no new intersection, a pass-through held back."""

import re

import numpy as np
import pytest

from conftest import ROOT, grid_sheet
from posefix.mesh.contact_solver import ContactResult, ContactSettings, ContactSolver
from posefix.mesh.geometry import face_areas
from posefix.mesh.primitives import capsule
from posefix.mesh.topology import grow_rings, vertex_adjacency
from posefix.mesh.distortion import SEVERE, distortion_summary, face_distortion
from posefix.mesh.intersections import intersecting_faces, self_intersecting_pairs
from posefix.mesh.rotations import rotation_exp
from posefix.verify import contact_finish as cf
from posefix.verify.contact_finish import FinishSettings
from posefix.verify.flags import CONTACT, REPLACED_NEW_INTERSECTION, REPRODUCED
from posefix.verify.sequence import finish_pose, repair_pose
from posefix.verify.state import RepairProblem
from test_sequence import _expand


def _sheets(upper_target):
    """A lower and an upper 9 x 9 sheet 0.1 apart; the lower one is V_C and stays, the upper one is free and
    goes to ``upper_target`` (81, 3)."""
    V1, F1 = grid_sheet(9, 0.0)
    V2, F2 = grid_sheet(9, 0.1)
    V, F = np.vstack([V1, V2]), np.vstack([F1, F2 + len(V1)])
    target = np.vstack([V1, upper_target])
    mask = np.arange(len(V)) < len(V1)
    pairs = [self_intersecting_pairs(P, F) for P in (V, target)]
    return V, F, RepairProblem.build(V, target, F, mask, pairs)


@pytest.mark.parametrize("free_goal, tolerance", [("elastic", 1e-6), ("blend", 1e-9)])
def test_a_rigid_motion_of_the_targets_comes_back_exactly(free_goal, tolerance):
    """V_C exactly; the free region up to Newton's stopping tolerance (elastic) or exactly (the positional goal's
    quadratic energy is solved in one step)."""
    V, F, _ = _sheets(grid_sheet(9, 0.1)[0])
    R = rotation_exp(np.array([[0.3, 0.1, -0.2]]))[0]
    target = V @ R.T + [0.2, 0.1, -0.3]
    mask = np.arange(len(V)) % 3 > 0
    problem = RepairProblem.build(V, target, F, mask, [np.zeros((0, 2), int)] * 2)
    samples = np.stack([V, 0.5 * (V + target), target + 1e-4])  # the integration missed by 1e-4
    result = finish_pose(problem, samples, 1.0, ContactSolver(V, F), FinishSettings(free_goal=free_goal))
    assert np.abs(result.X - target).max() < tolerance
    assert np.array_equal(result.X[mask], target[mask]) and (result.replaced[mask] == REPRODUCED).all()
    assert result.metrics["repaired_new"] == 0 and result.metrics["contact_samples_tracked"] == 0


def test_a_pass_through_stays_on_the_intersection_free_side():
    upper = grid_sheet(9, 0.0)[0]
    upper[:, 2] = -0.1 + 0.2 * upper[:, 0]  # tilted through the lower sheet: crosses it at x = 0.5
    V, F, problem = _sheets(upper)
    assert problem.target_faces.any() and not problem.reference_faces.any()
    t = np.linspace(0, 1, 5)[:, None, None]
    samples = (1 - t) * V + t * problem.V_tgt  # the integrated path lines pass through the lower sheet
    solver = ContactSolver(V, F)
    result = finish_pose(problem, samples, 1.0, solver)
    faces = intersecting_faces(self_intersecting_pairs(result.X, F), len(F))
    assert not faces.any() and result.metrics["repaired_new"] == 0
    assert result.metrics["contact_samples_tracked"] >= 1
    contact = (result.replaced & CONTACT) > 0
    assert contact.any() and np.abs(result.X[problem.mask] - V[problem.mask]).max() <= 1e-6
    apart = problem.mask & ~contact
    assert apart.any() and np.array_equal(result.X[apart], V[apart])  # V_C exact away from the contacts
    upper_z = result.X[~problem.mask, 2]
    assert upper_z.min() > 0.0  # held above the lower sheet
    # where the target is above the lower sheet, the free sheet reaches it
    above = problem.V_tgt[~problem.mask, 2] > 0.05
    assert np.abs(result.X[~problem.mask][above] - problem.V_tgt[~problem.mask][above]).max() < 0.05


@pytest.mark.parametrize("depth, held", [(-0.02, 14), (-0.05, 1)])
def test_v_c_goes_exactly_onto_its_targets_but_where_its_move_would_collide(depth, held):
    """Every constrained vertex moves onto its target but the one whose move crosses the lower sheet and the
    vertices of the pairs it collides with on the way (its ring and the faces under it): one blocked vertex does
    not hold back the rest. A move longer than the mean edge length (0.14; to ``depth`` -0.05) is not checked pair
    by pair: that vertex alone stays."""
    V, F, _ = _sheets(grid_sheet(9, 0.1)[0])
    target = V + [0.0, 0.0, 1e-3]
    centre = 81 + 40  # the upper sheet's middle vertex, whose target lies under the lower sheet
    target[centre, 2] = depth
    mask = np.ones(len(V), dtype=bool)
    problem = RepairProblem.build(V, target, F, mask, [np.zeros((0, 2), int)] * 2)
    none = np.zeros(len(V), dtype=bool)
    X, exact = cf._exact_constrained(problem, ContactSolver(V, F), V, none, none)
    rings = grow_rings(np.isin(np.arange(len(V)), [centre, centre - 81]), problem.A, 1)  # and the one under it
    assert not exact[centre] and exact[~rings].all() and exact.sum() == len(V) - held
    assert np.array_equal(X[exact], target[exact]) and np.array_equal(X[~exact], V[~exact])
    assert not self_intersecting_pairs(X, F).size


def test_the_contact_finish_metrics_are_the_documented_ones():
    V, F, problem = _sheets(grid_sheet(9, 0.1)[0])
    metrics = finish_pose(problem, np.stack([V, V]), 1.0, ContactSolver(V, F)).metrics
    section = (ROOT / "docs" / "artifacts.md").read_text().split("## verify")[1].split("## export")[0]
    listed = section.split("Metrics:")[1].split("Timings:")[0] + section.split("adds the metrics")[1]
    assert set(metrics) == {n for token in re.findall(r"`([a-z_{},0-9]+)`", listed) for n in _expand(token)}


def _fold(V, hinge, angle, radius=0.05):
    """The flat strip ``V`` folded up by ``angle`` (radians) at x = ``hinge`` round a hinge of ``radius``."""
    s = V[:, 0] - hinge
    bend, beyond = np.clip(s / radius, 0, angle), np.maximum(s - radius * angle, 0)
    T = V.copy()
    T[:, 0] = np.where(s <= 0, V[:, 0], hinge + radius * np.sin(bend) + beyond * np.cos(angle))
    T[:, 2] = np.where(s <= 0, 0.0, radius * (1 - np.cos(bend)) + beyond * np.sin(angle))
    return T


def _folded_strip(hinge):
    """A 1 x 0.15 strip (21 x 4 vertices) and its target folded back over itself at x = ``hinge`` (a round hinge
    of radius 0.05, the tip 0.1 above the base); V_C: both ends (x <= 0.2 and x >= 0.8)."""
    x, y = np.meshgrid(np.linspace(0, 1, 21), np.linspace(0, 0.15, 4), indexing="ij")
    V = np.column_stack([x.ravel(), y.ravel(), np.zeros(x.size)])
    F = np.array([[i * 4 + j, (i + 1) * 4 + j, (i + 1) * 4 + j + 1] for i in range(20) for j in range(3)]
                 + [[i * 4 + j, (i + 1) * 4 + j + 1, i * 4 + j + 1] for i in range(20) for j in range(3)])
    mask = (V[:, 0] <= 0.2) | (V[:, 0] >= 0.8)
    none = np.zeros((0, 2), dtype=np.int64)
    return V, F, RepairProblem.build(V, _fold(V, hinge, np.pi), F, mask, [none, none])


def test_the_distortion_metric_flags_the_snap_stretching_a_fold_and_not_the_contact_finish():
    """The field left the fold behind (the path lines fold the tip up by 18 degrees of 180): the snap puts the tip
    on its target and blends the rest, stretching the middle; the contact finish folds it as the target."""
    V, F, problem = _folded_strip(0.5)
    samples = np.stack([_fold(V, 0.5, 0.1 * np.pi * k / 4) for k in range(5)])
    rests = {"target": problem.V_tgt, "reference": V}
    snap = repair_pose(problem, samples[-1], 1.0, 1e-4, 1.0)  # the fit's error lets the snap reach the tip's target
    flagged = distortion_summary(snap.X, rests, F)
    assert snap.metrics["repaired_new"] == 0 and flagged["faces_over"] > 0 and flagged["edge_target"] > 4.0
    contact = finish_pose(problem, samples, 1.0, ContactSolver(V, F))  # free goal: elastic
    clean = distortion_summary(contact.X, rests, F)
    assert contact.metrics["repaired_new"] == 0 and clean["faces_over"] == 0 and clean["edge_target"] < 1.1
    target = finish_pose(problem, samples, 1.0, ContactSolver(V, F), FinishSettings(free_goal="target"))
    exact = distortion_summary(target.X, rests, F)
    assert target.metrics["repaired_new"] == 0 and exact["faces_over"] == 0 and exact["edge_target"] < 1.01


def test_a_finish_that_crushes_the_strip_past_ccd_is_reverted_to_an_intersection_free_sample():
    """Folded at x = 0.3 the tip's target lies beyond the base: with the smallest barrier distance, one straight
    Newton solve from the flat strip toward the target alone (free goal ``target``) crumples it (zero-area
    triangles, below CCD's precision), and the result is checked and reverted."""
    V, F, problem = _folded_strip(0.3)
    solver = ContactSolver(V, F, settings=ContactSettings(dhat=2e-4, tolerance=1e-4, max_iterations=40))  # crossed by then
    result = finish_pose(problem, np.stack([V, V]), 1.0, solver, FinishSettings(free_goal="target"))
    assert result.metrics["repaired_new"] == 0 and result.metrics["contact_reverted"]
    assert np.array_equal(result.X, V) and not (result.replaced & CONTACT).any()  # the intersection-free sample


def _standing_sheet(n, height):
    """A 9 x 9 sheet A at z = 0 and an n x n sheet B standing through it (x = 0.55, z from -0.2 to
    ``height`` - 0.2), apart in the target (B moved 0.8 along x, past A's edge): ``(V, F, target, pairs)``."""
    A, FA = grid_sheet(9, 0.0)
    U, FB = grid_sheet(n, 0.0)
    B = np.column_stack([np.full(len(U), 0.55), 0.3 + 0.4 * U[:, 0], -0.2 + height * U[:, 1]])
    V, F = np.vstack([A, B]), np.vstack([FA, FB + len(A)])
    target = V + (np.arange(len(V)) >= len(A))[:, None] * [0.8, 0.0, 0.0]
    return V, F, target, [self_intersecting_pairs(P, F) for P in (V, target)]


@pytest.mark.parametrize("free_goal", ["elastic", "blend"])
def test_where_the_target_undoes_the_references_own_intersection_that_region_takes_the_target(free_goal):
    """A 5 x 5 sheet stands through a 9 x 9 one in the reference (tolerated) and clear of it in the target (moved
    0.8 along x, past its edge): no intersection-free motion from the integrated pose (the reference) slides it
    out through the other sheet's clean faces, so the region around the reference's own intersection, grown by
    rings until it adds none, takes the target's positions (flag 2). The constrained vertices held off their
    targets by contacts with the region before it moved are exact after it (7 were 4.8e-7 off). The elastic finish
    pins the sheet's vertices off the reference's intersecting faces on their targets first: the untangling moves
    the rest."""
    V, F, target, pairs = _standing_sheet(5, 0.4)
    assert len(pairs[0]) > 0 and len(pairs[1]) == 0
    problem = RepairProblem.build(V, target, F, np.ones(len(V), bool), pairs)
    result = finish_pose(problem, np.stack([V, V]), 1.0, ContactSolver(V, F, problem.frame_pairs[0]),
                         FinishSettings(free_goal=free_goal))
    untangled = result.metrics["contact_untangled"]
    assert result.metrics["repaired_new"] == 0 and 0 < untangled <= 25
    assert free_goal == "elastic" or untangled == 25  # B: 5 x 5
    assert np.array_equal(result.X, target)
    assert ((result.replaced & REPLACED_NEW_INTERSECTION) > 0).sum() == untangled


def test_the_free_region_beside_an_untangled_region_follows_it_onto_the_target():
    """A sheet B stands through sheet A in the reference and clear of it in the target (moved 0.8 along x), as
    above; B's rows between 0.1 and 0.3 above A are free, the rows above them V_C (on the target from the start).
    The region around the reference's own intersection takes the target's positions after the elastic solve; the
    free rows, held between it and the top rows until then (0.36 off the target, faces 3.8x stretched), follow it
    (cat-09: faces 6-9x before the free region relaxed around the untangled one)."""
    V, F, target, pairs = _standing_sheet(9, 0.8)
    mask = (V[:, 2] <= 1e-9) | (V[:, 2] >= 0.4 - 1e-9)
    problem = RepairProblem.build(V, target, F, mask, pairs)
    result = finish_pose(problem, np.stack([V, V]), 1.0, ContactSolver(V, F, problem.frame_pairs[0]),
                         FinishSettings())
    assert result.metrics["repaired_new"] == 0 and result.metrics["contact_untangled"] > 0
    assert face_distortion(result.X, target, F)[0].max() < 1.5
    assert np.abs(result.X[~mask] - target[~mask]).max() < 0.01


def _bent(V, angle, joint=1.5):
    """``V`` turned by ``angle`` (rad) about the z axis, blended linearly over |x| < ``joint``: an elbow."""
    t = np.clip((V[:, 0] + joint) / (2 * joint), 0.0, 1.0)
    c, s = np.cos(angle * t), np.sin(angle * t)
    return np.column_stack([c * V[:, 0] - s * V[:, 1], s * V[:, 0] + c * V[:, 1], V[:, 2]])


def test_a_cylinder_bent_150_degrees_is_repaired_without_a_crushed_face():
    """The halves of a capsule bent 150 degrees pass through each other beyond the elbow; V_C is all but the
    intersecting faces grown by 2 rings (as classify makes it); the integrated path lines are the key frames."""
    V, F = capsule(around=16, cap_rings=3, length_rings=24)
    frames = np.stack([_bent(V, np.radians(a)) for a in np.linspace(0.0, 150.0, 11)])
    pairs = [self_intersecting_pairs(P, F) for P in (V, frames[-1])]
    free = np.zeros(len(V), dtype=bool)
    free[F[intersecting_faces(pairs[1], len(F))].ravel()] = True
    problem = RepairProblem.build(V, frames[-1], F, ~grow_rings(free, vertex_adjacency(F, len(V)), 2), pairs)
    assert len(pairs[1]) > 0 and problem.mask.sum() < len(V)
    result = finish_pose(problem, frames, 1.0, ContactSolver(V, F), FinishSettings(), frames)
    assert len(self_intersecting_pairs(result.X, F)) == 0 and result.metrics["contact_converged"]
    assert (face_areas(result.X, F) / face_areas(V, F)).min() > 0.25
    apart = problem.mask & ((result.replaced & CONTACT) == 0)
    assert np.array_equal(result.X[apart], problem.V_tgt[apart])  # V_C exact away from the contacts


def _turned(V, angle, joint=-1.0):
    """``V``'s part beyond x = ``joint`` turned by ``angle`` (rad) about the z axis through (joint, 0, 0)."""
    c, s = np.cos(angle), np.sin(angle)
    X = V.copy()
    beyond = V[:, 0] > joint
    x, y = V[beyond, 0] - joint, V[beyond, 1]
    X[beyond, 0], X[beyond, 1] = joint + c * x - s * y, s * x + c * y
    return X


def test_a_finger_whose_path_lines_pass_under_its_neighbour_ends_unstretched():
    """A finger (capsule A) turns 20 degrees into its neighbour B; V_C is B and A's base. The key frames turn A in
    its plane; the integrated path lines, built to be caught on the wrong side, first dive under B and then turn,
    so the integrated pose has A's tip under B and the skin at the base stretched 13x. The elastic finish starts
    from the tracked key frames (lower energy) and ends within 4x of the target, beside B in the target's plane
    (from the integrated pose it unstretches too, but with the tip still 0.36 under that plane); the positional
    finish keeps the stretch."""
    A, FA = capsule(around=12, cap_rings=3, length_rings=24)
    V, F = np.vstack([A, A + [0.0, 1.4, 0.0]]), np.vstack([FA, FA + len(A)])
    finger = np.arange(len(V)) < len(A)

    def pose(angle, dive):
        X = V.copy()
        X[finger] = _turned(A, angle)
        X[finger, 2] += dive * np.clip((A[:, 0] + 1.0) / 0.2, 0.0, 1.0)
        return X

    t = np.linspace(0.0, 1.0, 11)
    frames = np.stack([pose(np.radians(20.0) * k, 0.0) for k in t])
    samples = np.stack([pose(np.radians(20.0) * max(0.0, 2 * k - 1), -1.1 * min(1.0, 2 * k)) for k in t])
    pairs = [self_intersecting_pairs(P, F) for P in (V, frames[-1])]
    problem = RepairProblem.build(V, frames[-1], F, ~finger | (V[:, 0] < -1.0), pairs)
    assert len(pairs[1]) and not any(len(self_intersecting_pairs(S, F)) for S in samples)
    assert face_distortion(samples[-1], frames[-1], F)[0].max() > 10.0
    elastic = finish_pose(problem, samples, 1.0, ContactSolver(V, F), FinishSettings(), frames)
    assert elastic.metrics["repaired_new"] == 0 and elastic.metrics["contact_start"] == "tracked"
    assert face_distortion(elastic.X, frames[-1], F)[0].max() < 4.0
    assert abs(elastic.X[finger & (V[:, 0] > 2.0), 2].mean()) < 0.2  # beside B (0.12 with k_b 1), not under it (0.36)
    positional = finish_pose(problem, samples, 1.0, ContactSolver(V, F), FinishSettings(free_goal="blend"), frames)
    assert face_distortion(positional.X, frames[-1], F)[0].max() > 10.0


def test_each_free_region_starts_from_the_candidate_of_lower_energy():
    """Two fingers, far apart, each turning 20 degrees into its neighbour (V_C: the neighbours and the bases). The
    first finger's path lines dive under its neighbour (the tracked key frames do not); the second's key frames
    dive, and its path lines turn a quarter of the way (5 degrees), beside the neighbour. Each free region (a fingertip) starts from the candidate where it is not caught:
    the start is the tracked one with the second region integrated, and both tips end beside their neighbours,
    within 4x of the target."""
    A, FA = capsule(around=12, cap_rings=3, length_rings=24)
    V = np.vstack([A, A + [0.0, 1.4, 0.0], A + [0.0, 0.0, 10.0], A + [0.0, 1.4, 10.0]])
    F = np.vstack([FA + k * len(A) for k in range(4)])
    fingers = [np.arange(len(V)) // len(A) == k for k in (0, 2)]

    def pose(angles, dives):
        X = V.copy()
        for finger, angle, dive in zip(fingers, angles, dives):
            X[finger] = _turned(V[finger], angle)
            X[finger, 2] += dive * np.clip((A[:, 0] + 1.0) / 0.2, 0.0, 1.0)
        return X

    t, turn = np.linspace(0.0, 1.0, 11), np.radians(20.0)
    caught = [(turn * max(0.0, 2 * k - 1), -1.1 * min(1.0, 2 * k)) for k in t]  # dive, then turn
    frames = np.stack([pose((turn * k, c[0]), (0.0, c[1])) for k, c in zip(t, caught)])
    samples = np.stack([pose((c[0], 0.25 * turn * k), (c[1], 0.0)) for k, c in zip(t, caught)])
    target = pose((turn, turn), (0.0, 0.0))
    frames[-1] = target
    pairs = [self_intersecting_pairs(P, F) for P in (V, target)]
    free = (fingers[0] | fingers[1]) & (np.tile(A[:, 0], 4) >= -1.0)
    problem = RepairProblem.build(V, target, F, ~free, pairs)
    assert not any(len(self_intersecting_pairs(S, F)) for S in samples)
    result = finish_pose(problem, samples, 1.0, ContactSolver(V, F), FinishSettings(), frames)
    assert result.metrics["repaired_new"] == 0
    assert result.metrics["contact_start"] == "tracked, 1 of 2 free regions integrated"
    assert face_distortion(result.X, target, F)[0].max() < 4.0
    for finger, z in zip(fingers, (0.0, 10.0)):  # each tip beside its neighbour, not under it
        assert abs(result.X[finger & (np.tile(A[:, 0], 4) > 2.0), 2].mean() - z) < 0.2


def test_a_free_region_pushed_out_of_shape_is_solved_again_from_the_other_start_and_the_better_kept():
    """A 9 x 9 sheet, its border V_C, the target the reference. A first result with a free vertex dragged 0.5 off
    (its faces beyond 10x, as a contact that caught it would leave it) is out of shape; the solve from the other
    start (the reference) comes back onto the target and is kept, with fewer severe faces. A clean first result
    is kept against a spiked other start: between results with as many severe faces the lower energy wins, and
    before it the converged one."""
    V, F = grid_sheet(9, 0.0)
    border = (V[:, 0] % 1.0 == 0.0) | (V[:, 1] % 1.0 == 0.0)
    problem = RepairProblem.build(V, V, F, border, [self_intersecting_pairs(V, F)] * 2)
    solver, settings = ContactSolver(V, F), FinishSettings()
    motion, locked = cf._motion(problem, V, settings), np.zeros(len(V), dtype=bool)
    spiked = V.copy()
    spiked[40, 2] += 0.5  # the centre
    assert cf._out_of_shape(problem, spiked, settings.rest_limit) and not cf._out_of_shape(problem, V, 3.0)
    first = ContactResult(spiked, True, 7, np.zeros(len(V), dtype=bool), np.inf, 0.0)
    weights = (border, locked, settings.constrained_weight, settings.second_iterations)
    result, label = cf._lower_energy_result(problem, solver, motion, (first, "tracked"), (V, "integrated"), weights)
    assert label == "integrated (second start)" and result.iterations >= 7
    np.testing.assert_allclose(result.X, V, atol=1e-9)
    clean = ContactResult(V.copy(), True, 1, np.zeros(len(V), dtype=bool), np.inf, 0.0)
    kept, label = cf._lower_energy_result(problem, solver, motion, (clean, "tracked"), (spiked, "integrated"),
                                          weights)
    assert label == "tracked" and np.array_equal(kept.X, V)
    crept = ContactResult(V.copy(), False, 400, np.zeros(len(V), dtype=bool), np.inf, 0.0)  # the lowest energy, 0
    bumped = V.copy()
    bumped[40, 2] += 0.01
    kept, label = cf._lower_energy_result(problem, solver, motion, (crept, "tracked"), (bumped, "integrated"),
                                          weights)
    assert label == "integrated (second start)" and kept.converged  # no severe face either way: converged first


def test_a_second_solve_stopped_by_its_iteration_cap_is_not_kept_over_a_converged_first():
    """The sheet of the test above, its first result out of shape (its centre 2 off: 6 faces beyond 10x) but
    converged, the other start its centre 0.2 off. Stopped after one Newton iteration, the second solve is still on
    its way (not converged, 0.05 off, no face beyond 10x): the converged first is kept, though it has more faces
    beyond 10x. With the default cap the second converges onto the target and is kept."""
    V, F = grid_sheet(9, 0.0)
    border = (V[:, 0] % 1.0 == 0.0) | (V[:, 1] % 1.0 == 0.0)
    problem = RepairProblem.build(V, V, F, border, [self_intersecting_pairs(V, F)] * 2)
    solver, settings = ContactSolver(V, F), FinishSettings()
    motion, locked = cf._motion(problem, V, settings), np.zeros(len(V), dtype=bool)
    spiked, bumped = V.copy(), V.copy()
    spiked[40, 2] += 2.0
    bumped[40, 2] += 0.2
    assert cf._pushed(problem, spiked, SEVERE).sum() == 6 and not cf._pushed(problem, bumped, SEVERE).any()
    first = ContactResult(spiked, True, 7, np.zeros(len(V), dtype=bool), np.inf, 0.0)
    for most, label in ((1, "tracked"), (settings.second_iterations, "integrated (second start)")):
        kept, kept_label = cf._lower_energy_result(problem, solver, motion, (first, "tracked"), (bumped, "integrated"),
                                                   (border, locked, settings.constrained_weight, most))
        assert kept_label == label and kept.converged and kept.iterations <= 7 + most


def test_the_second_solve_runs_only_where_the_first_result_would_not_make_the_pose_ok():
    """A 9 x 9 sheet, its border V_C. Its centre raised so that its 6 faces are 2-4x the target's: ok (no second
    solve, the status's limit being 4, where the rest limit of 2 ran one); raised more, beyond 4x: not ok; flat but
    not converged: not ok."""
    V, F = grid_sheet(9, 0.0)
    border = (V[:, 0] % 1.0 == 0.0) | (V[:, 1] % 1.0 == 0.0)
    problem = RepairProblem.build(V, V, F, border, [self_intersecting_pairs(V, F)] * 2)
    none = np.zeros(len(V), dtype=bool)
    around = np.isin(F, 40).any(axis=1)
    for rise, ok in ((0.3, True), (0.5, False)):
        X = V.copy()
        X[40, 2] += rise
        ratios = np.maximum(*face_distortion(X, V, F))[around]  # 2.6-3.5, then 4.1-5.7
        assert (2.0 < ratios.min() and ratios.max() < 4.0) if ok else 4.0 < ratios.min() < 10.0
        assert cf._out_of_shape(problem, X, FinishSettings().rest_limit)  # the old bound ran the second solve
        assert cf._not_ok(problem, ContactResult(X, True, 9, none, np.inf, 0.0)) != ok
    assert cf._not_ok(problem, ContactResult(V, False, 400, none, np.inf, 0.0))


def test_where_no_sample_after_the_reference_is_intersection_free_the_start_is_the_tracked_key_frames_alone():
    """The finger of the test above, its path lines through its neighbour from the first sample on (the finger
    shifted halfway into it): nothing of the integration is intersection-free, so the elastic finish starts from
    the key frames tracked, and the contact solver tracks no path through the samples (one path: the key frames'),
    to a result with no new intersecting face, within 4x of the target."""
    A, FA = capsule(around=12, cap_rings=3, length_rings=24)
    V, F = np.vstack([A, A + [0.0, 1.4, 0.0]]), np.vstack([FA, FA + len(A)])
    finger = np.arange(len(V)) < len(A)
    t = np.linspace(0.0, 1.0, 11)
    frames = np.stack([np.where(finger[:, None], np.vstack([_turned(A, np.radians(20.0) * k), A]), V) for k in t])
    samples = frames.copy()
    samples[1:, finger] += [0.0, 0.7, 0.0]
    pairs = [self_intersecting_pairs(P, F) for P in (V, frames[-1])]
    problem = RepairProblem.build(V, frames[-1], F, ~finger | (V[:, 0] < -1.0), pairs)
    assert all(len(self_intersecting_pairs(S, F)) for S in samples[1:])
    solver, paths = ContactSolver(V, F), []
    compute_path = solver.compute_path
    solver.compute_path = lambda start, waypoints, *args, **kwargs: (paths.append(len(waypoints)),
                                                                     compute_path(start, waypoints, *args, **kwargs))[1]
    result = finish_pose(problem, samples, 1.0, solver, FinishSettings(), frames)
    assert paths == [len(frames) - 1] and result.metrics["contact_start"] == "tracked"
    assert result.metrics["repaired_new"] == 0 and result.metrics["contact_samples_tracked"] == len(samples) - 1
    assert face_distortion(result.X, frames[-1], F)[0].max() < 4.0
