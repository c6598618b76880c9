"""Text rows shared by the text formats."""

from posefix.io.errors import InputError


def rows(prefix, A, fmt):
    """Text lines ``prefix + fmt % row`` for every row of ``A`` (k, c), str."""
    return "".join(prefix + (fmt % tuple(row)) + "\n" for row in A.tolist())


def check_vertex_rows(path, body, declared, width):
    """Raise :class:`~posefix.io.errors.InputError` when a header's vertex count ``declared`` is not the number of
    leading rows of ``body`` (bytes after the header) that have ``width`` numbers: trimesh would read face rows as
    vertices (or vertex rows as faces), and the problem would show as something else. Face rows have a count and
    that many indices, so ``width`` must not be 4 (the caller does not check then)."""
    lines = [line.split() for line in body.splitlines() if line.strip()]
    plain = next((k for k, row in enumerate(lines) if len(row) != width), len(lines))
    if lines and plain != declared:
        raise InputError(path, f"the header declares {declared} vertices but the file has {plain} vertex rows")
