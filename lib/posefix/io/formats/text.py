"""Text rows shared by the text formats."""


def rows(prefix, A, fmt):
    """Text lines ``prefix + fmt % row`` for every row of ``A`` (k, c), str."""
    return "".join(prefix + (fmt % tuple(row)) + "\n" for row in A.tolist())
