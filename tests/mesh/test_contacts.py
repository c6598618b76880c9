"""Near contacts: close but geodesically distant surfaces."""

import numpy as np

from conftest import icosphere
import posefix.mesh.contacts as contacts_module
from posefix.mesh.contacts import contact_vertices
from posefix.spacetime.classification import EXCLUDED_CONTACT, constraint_mask


def test_contacts_flag_close_distant_surfaces_only():
    # two parallel unit spheres' caps: a sphere and a copy 2.05 apart along x nearly touch
    V1, F1 = icosphere(3)
    V2, F2 = icosphere(3, centre=(2.05, 0.0, 0.0))
    V, F = np.vstack([V1, V2]), np.vstack([F1, F2 + len(V1)])
    far = V.copy()
    far[len(V1):] += [3.0, 0.0, 0.0]
    frames = np.stack([far, V])  # reference far apart, then close
    contacts = contact_vertices(frames, F, far, distance=0.1, radius=0.5)
    assert not contacts[0].any()
    close = np.flatnonzero(contacts[1])
    assert len(close) > 0
    gap = np.where(np.arange(len(V)) < len(V1), 1.025 - V[:, 0], V[:, 0] - 1.025)
    assert np.all(gap[close] < 0.1 + 0.03)  # only vertices near the gap plane x = 1.025
    # within one sphere nothing is in contact: its own surface is geodesically near or far away
    alone = contact_vertices(V1[None], F1, V1, distance=0.1, radius=0.5)
    assert not alone.any()
    mask, reasons = constraint_mask(F, len(V), [np.zeros((0, 2), int)] * 2, ring=1, contacts=contacts)
    assert np.array_equal(reasons & EXCLUDED_CONTACT > 0, contacts[1])
    assert not mask[close].any()


def test_contacts_looked_at_in_chunks_are_the_same(monkeypatch):
    # two spheres nearly touching, one moving: their close pairs checked 64 at a time or all at once
    V1, F1 = icosphere(3)
    V2, F2 = icosphere(2, centre=(2.02, 0.3, 0.0))
    V, F = np.vstack([V1, V2]), np.vstack([F1, F2 + len(V1)])
    frames = np.stack([V + [[k * 0.01, 0.0, 0.0]] * (np.arange(len(V)) < len(V1))[:, None] for k in range(3)])
    whole = contact_vertices(frames, F, V, distance=0.15, radius=0.5)
    monkeypatch.setattr(contacts_module, "_CHUNK", 64)
    assert whole.any() and np.array_equal(contact_vertices(frames, F, V, distance=0.15, radius=0.5), whole)


def test_non_neighbouring_on_the_vertices_around_each_chunk_is_the_whole_graphs():
    """Dijkstra on the vertices within the radius of a chunk's box gives the whole graph's answer: every pair of a
    sphere's vertices and faces, 16 sources a chunk, against the whole graph's distances."""
    from scipy.sparse.csgraph import dijkstra

    V, F = icosphere(3)
    graph = contacts_module.edge_graph(V, F)
    rng = np.random.default_rng(0)
    pairs = np.stack([rng.integers(0, len(V), 4000), rng.integers(0, len(F), 4000)], axis=1)
    for radius in (0.2, 0.7, 3.0):
        whole = dijkstra(graph, directed=False, limit=radius)
        expected = whole[pairs[:, :1], F[pairs[:, 1]]].min(axis=1) >= radius
        got = contacts_module.non_neighbouring(pairs, F, graph, radius, V, rows=16)
        assert 0 < expected.sum() < len(pairs) or radius == 3.0
        assert np.array_equal(got, expected)
