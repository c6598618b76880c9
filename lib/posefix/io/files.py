"""Writing files atomically (temporary name, then rename), file hashes, figures as PNG files, YAML inputs."""

import hashlib
import io
import os
import tempfile
from contextlib import contextmanager
from pathlib import Path

import yaml

from posefix.io.errors import InputError


@contextmanager
def atomic_path(path):
    """A temporary path next to ``path`` to write to; renamed to ``path`` when the block succeeds.

    The parent folder is created. On any exception the temporary file is removed and ``path`` is
    left untouched, so a reader never sees a partial file; an ``OSError`` that names no file (a full
    disk) is raised again naming ``path``.

    Examples
    --------
    >>> with atomic_path("out.bin") as tmp:  # doctest: +SKIP
    ...     Path(tmp).write_bytes(b"data")
    """
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    fd, tmp = tempfile.mkstemp(prefix=f".{path.name}.", suffix=".tmp", dir=path.parent)
    os.close(fd)
    try:
        yield tmp
        _publish(tmp, path)
    except OSError as exc:  # a full disk says "No space left on device" without a file: name the one written
        if exc.filename not in (None, tmp):
            raise
        raise OSError(exc.errno, exc.strerror or str(exc), str(path)) from exc
    finally:
        if os.path.exists(tmp):
            os.unlink(tmp)


def atomic_write_bytes(path, data):
    """Write ``data`` (bytes) to ``path`` atomically (:func:`atomic_path`)."""
    with atomic_path(path) as tmp:
        with open(tmp, "wb") as fh:
            fh.write(data)


def _publish(tmp, path):
    """Give a finished temporary file the usual permissions (0666 minus umask), rename it to ``path``."""
    umask = os.umask(0)
    os.umask(umask)
    os.chmod(tmp, 0o666 & ~umask)
    os.replace(tmp, path)


def write_figure(path, fig):
    """Write a matplotlib ``Figure`` as PNG, atomically (same bytes for the same figure)."""
    buffer = io.BytesIO()
    fig.savefig(buffer, format="png", metadata={"Software": None})
    atomic_write_bytes(path, buffer.getvalue())


def file_sha256(path):
    """Hex sha256 of a file's bytes."""
    h = hashlib.sha256()
    with open(path, "rb") as fh:
        for block in iter(lambda: fh.read(1 << 20), b""):
            h.update(block)
    return h.hexdigest()


def read_yaml(path):
    """The YAML document of a file (rig files, pose scripts); :class:`InputError` naming it when it cannot be
    opened or parsed."""
    try:
        with open(path, encoding="utf-8") as fh:
            return yaml.safe_load(fh)
    except OSError as exc:
        raise InputError(path, f"cannot be opened: {exc.strerror or exc}") from None
    except yaml.YAMLError as exc:
        raise InputError(path, f"not valid YAML: {str(exc).splitlines()[0]}") from None
