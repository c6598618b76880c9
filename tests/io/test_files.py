"""Atomic file writing, hashes and figures."""

import hashlib
import os
from pathlib import Path

import pytest
from matplotlib.figure import Figure

from posefix.io.files import atomic_path, atomic_write_bytes, file_sha256, write_figure


def test_atomic_write_creates_folders_and_replaces_whole_files(tmp_path):
    path = tmp_path / "sub" / "f.bin"
    atomic_write_bytes(path, b"one")
    atomic_write_bytes(path, b"two")
    assert path.read_bytes() == b"two" and os.listdir(path.parent) == ["f.bin"]
    assert oct(path.stat().st_mode & 0o777) == oct(0o666 & ~_umask())


def test_an_exception_inside_leaves_nothing_behind(tmp_path):
    path = tmp_path / "f.bin"
    path.write_bytes(b"old")
    with pytest.raises(RuntimeError):
        with atomic_path(path) as tmp:
            open(tmp, "wb").write(b"partial")
            raise RuntimeError("killed")
    assert path.read_bytes() == b"old" and os.listdir(tmp_path) == ["f.bin"]


def test_sha256_and_deterministic_figures(tmp_path):
    (tmp_path / "x").write_bytes(b"abc")
    assert file_sha256(tmp_path / "x") == hashlib.sha256(b"abc").hexdigest()
    fig = Figure(figsize=(2, 2))
    fig.add_subplot().plot([0, 1], [1, 0])
    write_figure(tmp_path / "a.png", fig)
    write_figure(tmp_path / "b.png", fig)
    assert (tmp_path / "a.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    assert (tmp_path / "a.png").read_bytes() == (tmp_path / "b.png").read_bytes()


def _umask():
    mask = os.umask(0)
    os.umask(mask)
    return mask


def test_a_full_disk_names_the_file_being_written(tmp_path):
    import errno
    target = tmp_path / "out" / "fit.h5"
    with pytest.raises(OSError) as caught:
        with atomic_path(target) as tmp:
            Path(tmp).write_bytes(b"partial")
            raise OSError(errno.ENOSPC, "No space left on device")  # what a failed write() raises
    assert caught.value.filename == str(target) and caught.value.errno == errno.ENOSPC
    assert not any((tmp_path / "out").iterdir())
