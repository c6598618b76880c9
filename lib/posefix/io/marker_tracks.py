"""Motion-capture marker tracks (S4 §3.2 marker animation) from CSV or NPZ.

CSV: a header ``frame,marker,x,y,z``, then one row per frame and marker in any order; ``frame`` an
integer, ``marker`` a label (a reference vertex id when markers are attached by id). Every marker must
appear exactly once in every frame.

NPZ: an array ``tracks`` (frames x markers x 3), optionally ``markers`` (labels, default 0, 1, ...) and
``frames`` (integers, default 0, 1, ...).

Both give the same :class:`MarkerTracks` whatever the order of rows or columns: frames ascending, markers
sorted by label (as numbers when every label is an integer).
"""

import csv
import zipfile
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from posefix.io.errors import InputError

COLUMNS = ("frame", "marker", "x", "y", "z")


@dataclass
class MarkerTracks:
    """Marker tracks: ``frames`` (f,) int64, ``markers`` (p,) str labels, ``positions`` (f, p, 3) float64."""

    frames: np.ndarray
    markers: np.ndarray
    positions: np.ndarray


def read_tracks(path):
    """Read marker tracks from a ``.csv`` or ``.npz`` file; :class:`InputError` naming it and the problem."""
    suffix = Path(path).suffix.lower()
    if suffix == ".csv":
        tracks = _read_csv(path)
    elif suffix == ".npz":
        tracks = _read_npz(path)
    else:
        raise InputError(path, "marker tracks must be .csv (frame, marker, x, y, z) or .npz (tracks)")
    if not np.isfinite(tracks.positions).all():
        frame, marker = np.argwhere(~np.isfinite(tracks.positions).all(axis=2))[0]
        raise InputError(path, f"marker {tracks.markers[marker]} has no finite position in frame "
                               f"{tracks.frames[frame]}")
    if len(np.unique(tracks.frames)) < len(tracks.frames) or len(np.unique(tracks.markers)) < len(tracks.markers):
        raise InputError(path, "frame numbers and marker labels must be unique")
    numeric = all(m.lstrip("-").isdigit() for m in tracks.markers)
    markers = np.argsort([int(m) for m in tracks.markers] if numeric else tracks.markers, kind="stable")
    frames = np.argsort(tracks.frames, kind="stable")
    return MarkerTracks(tracks.frames[frames], tracks.markers[markers], tracks.positions[frames][:, markers])


def _read_csv(path):
    try:
        with open(path, newline="", encoding="utf-8") as fh:
            reader = csv.reader(fh)
            header = [c.strip().lower() for c in next(reader, [])]
            if tuple(header) != COLUMNS:
                raise InputError(path, f"header must be {','.join(COLUMNS)}, not {','.join(header) or 'empty'}")
            rows = [(line, r) for line, r in enumerate(reader, start=2) if r]
    except OSError as exc:
        raise InputError(path, f"cannot be opened: {exc.strerror or exc}") from None
    except UnicodeDecodeError:
        raise InputError(path, "not a text file") from None
    if not rows:
        raise InputError(path, "no marker positions")
    frames, markers, values = [], [], []
    for line, row in rows:
        if len(row) != 5:
            raise InputError(path, f"line {line}: {len(row)} fields, expected 5 ({','.join(COLUMNS)})")
        try:
            frames.append(int(row[0]))
            values.append([float(v) for v in row[2:]])
        except ValueError:
            raise InputError(path, f"line {line}: frame must be an integer and x, y, z numbers") from None
        markers.append(row[1].strip())
    frames, values = np.array(frames), np.array(values)
    frame_ids, frame_of = np.unique(frames, return_inverse=True)
    labels = list(dict.fromkeys(markers))
    index = {m: i for i, m in enumerate(labels)}
    marker_of = np.array([index[m] for m in markers])
    count = np.zeros((len(frame_ids), len(labels)), dtype=np.int64)
    np.add.at(count, (frame_of, marker_of), 1)
    if (count != 1).any():
        f, m = np.argwhere(count != 1)[0]
        raise InputError(path, f"marker {labels[m]} appears {count[f, m]} times in frame {frame_ids[f]} "
                               "(every marker exactly once per frame)")
    positions = np.empty((len(frame_ids), len(labels), 3))
    positions[frame_of, marker_of] = values
    return MarkerTracks(frame_ids.astype(np.int64), np.array(labels), positions)


def _read_npz(path):
    try:
        with np.load(path, allow_pickle=False) as data:
            if "tracks" not in data:
                raise InputError(path, f"no array 'tracks' (has: {', '.join(data.files) or 'none'})")
            positions = np.asarray(data["tracks"], dtype=np.float64)
            if positions.ndim != 3 or positions.shape[2] != 3 or 0 in positions.shape:
                raise InputError(path, f"'tracks' must be frames x markers x 3, not {positions.shape}")
            markers = data["markers"] if "markers" in data else np.arange(positions.shape[1])
            frames = data["frames"] if "frames" in data else np.arange(positions.shape[0])
    except (OSError, ValueError, zipfile.BadZipFile) as exc:
        raise InputError(path, f"cannot be read as NPZ: {str(exc).splitlines()[0]}") from None
    if markers.shape != positions.shape[1:2] or frames.shape != positions.shape[:1]:
        raise InputError(path, f"'markers' {markers.shape} and 'frames' {frames.shape} do not match 'tracks' "
                               f"{positions.shape}")
    if not np.issubdtype(frames.dtype, np.integer):
        raise InputError(path, "'frames' must be integers")
    return MarkerTracks(frames.astype(np.int64), np.array([str(m) for m in markers]), positions)


def write_tracks_csv(path, tracks):
    """Write :class:`MarkerTracks` as CSV (the format :func:`read_tracks` reads), frame by frame."""
    with open(path, "w", newline="", encoding="utf-8") as fh:
        writer = csv.writer(fh)
        writer.writerow(COLUMNS)
        for frame, row in zip(tracks.frames, tracks.positions):
            for marker, p in zip(tracks.markers, row):
                writer.writerow([int(frame), marker, *(repr(float(v)) for v in p)])
