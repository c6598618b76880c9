"""The sparse direct solver of posefix: one place to factorize the sparse systems of every method.

Laplacian and Poisson systems (harmonic extension, key frames, later the skeletal reconstruction
and the volumetric editor) and Gauss–Newton's normal equations all go through :func:`factorized`,
so that a faster back end replaces SuperLU in one place. :func:`cholesky_factorized` is that back end for
the large symmetric positive definite systems (the contact solver's Newton steps): CHOLMOD's supernodal
Cholesky (scikit-sparse, SuiteSparse) when it is installed, SuperLU's symmetric mode otherwise;
:class:`CholeskySequence` factorizes a sequence of matrices of one pattern (Gauss–Newton's steps) with one analysis.
"""

import functools
import logging
from types import SimpleNamespace

import numpy as np
import scipy.sparse as sp
from scipy.sparse.linalg import splu
from threadpoolctl import threadpool_info, threadpool_limits

log = logging.getLogger(__name__)


def factorized(A, ordering="COLAMD", symmetric=False):
    """A sparse LU factorization of ``A`` that solves ``A x = b`` for one or many right-hand sides.

    Parameters
    ----------
    A : (n, n) scipy.sparse matrix
        Square and non-singular (converted to CSC).
    ordering : str
        Fill-reducing column ordering of SuperLU (``COLAMD``, ``MMD_AT_PLUS_A``, ``MMD_ATA``, ``NATURAL``);
        ``MMD_AT_PLUS_A`` suits symmetric matrices.
    symmetric : bool
        ``A`` is symmetric positive (semi-)definite: pivot on the diagonal (SuperLU's symmetric mode),
        which keeps the ordering's fill low.

    Returns
    -------
    scipy.sparse.linalg.SuperLU
        ``.solve(b)`` with ``b`` (n,) or (n, k) float.

    Raises
    ------
    RuntimeError
        ``A`` is exactly singular.

    Examples
    --------
    >>> import numpy as np, scipy.sparse as sp
    >>> factorized(sp.diags([2.0, 4.0])).solve(np.array([1.0, 1.0])).tolist()
    [0.5, 0.25]
    """
    if symmetric:
        return splu(A.tocsc(), permc_spec=ordering, diag_pivot_thresh=0.0, options={"SymmetricMode": True})
    return splu(A.tocsc(), permc_spec=ordering)


def cholesky_factorized(A, order=None):
    """A Cholesky factorization of the symmetric positive definite ``A`` that solves ``A x = b``.

    CHOLMOD's supernodal Cholesky with its AMD ordering (``pip install posefix[cholmod]``, SuiteSparse's
    headers needed to build it) factorizes the contact solver's Newton system of a 60k-vertex pose
    (179k unknowns) in 2.4 s and 1.2 GB where SuperLU takes 89 s and 5.0 GB (README, "Memory and disk").
    Without it, SuperLU's symmetric mode in ``order``.

    Parameters
    ----------
    A : (n, n) scipy.sparse matrix
        Symmetric positive definite.
    order : (n,) int, optional
        SuperLU's elimination order when CHOLMOD is absent (see :func:`fill_reducing_order`); computed when
        not given.

    Returns
    -------
    object
        ``.solve(b)`` with ``b`` (n,) or (n, k) float.

    Raises
    ------
    numpy.linalg.LinAlgError
        ``A`` is not (numerically) positive definite.

    Examples
    --------
    >>> import numpy as np, scipy.sparse as sp
    >>> cholesky_factorized(sp.csc_matrix([[4.0, 1.0], [1.0, 3.0]])).solve(np.array([5.0, 4.0])).round(12).tolist()
    [1.0, 1.0]
    """
    A = sp.csc_matrix(A)
    analyze = _cholmod_analyze()
    if analyze is None:
        return _superlu_cholesky(A, fill_reducing_order(A) if order is None else order)
    from sksparse.cholmod import CholmodNotPositiveDefiniteError  # loaded already: analyze comes from it

    try:
        return SimpleNamespace(solve=analyze(A, mode="supernodal", ordering_method="amd").cholesky(A).solve_A)
    except CholmodNotPositiveDefiniteError as error:
        raise np.linalg.LinAlgError(str(error)) from error


class CholeskySequence:
    """Cholesky factorizations of a sequence of symmetric positive definite matrices whose sparsity patterns mostly
    repeat (Gauss–Newton's steps): CHOLMOD analyses a pattern once, with METIS's nested-dissection ordering, and
    factorizes every later matrix whose pattern lies within it numerically only.

    METIS's analysis costs more than AMD's and its factors have less fill, so it pays from the second matrix of a
    pattern on. On the 179k-unknown Newton matrix of the contact solver on kids-0001 (one thread): AMD 0.3 s of
    analysis and 1.7 s of factorization, METIS 1.6 s and 1.3 s. The contact solver factorizes anew
    (:func:`cholesky_factorized`): its contacts slide, and each Newton step brings hundreds of entries that lie
    outside the last pattern, most of them outside its factor's fill too. A matrix with an entry outside the analysed
    pattern is analysed again, with the union of the two patterns, unless the union has grown past
    :data:`PATTERN_GROWTH` times the new pattern. Without CHOLMOD, each matrix is factorized anew.

    Examples
    --------
    >>> import numpy as np, scipy.sparse as sp
    >>> sequence = CholeskySequence()
    >>> A = sp.csc_matrix([[4.0, 1.0], [1.0, 3.0]])
    >>> [sequence.factorized(k * A).solve(np.array([5.0, 4.0])).round(12).tolist() for k in (1.0, 2.0)]
    [[1.0, 1.0], [0.5, 0.5]]
    """

    def __init__(self):
        self.analyses, self._pattern, self._factor = 0, None, None

    def factorized(self, A, order=None):
        """A factorization of ``A`` (n, n) sparse, symmetric positive definite, as ``.solve(b)``: valid until the next
        call (the factor is updated in place).

        Parameters
        ----------
        A : (n, n) scipy.sparse matrix
        order : (n,) int, optional
            The elimination order without CHOLMOD (:func:`cholesky_factorized`).

        Raises
        ------
        numpy.linalg.LinAlgError
            ``A`` is not (numerically) positive definite.
        """
        A = sp.csc_matrix(A)
        if _cholmod_analyze() is None:
            return cholesky_factorized(A, order)
        from sksparse.cholmod import CholmodNotPositiveDefiniteError

        A.sort_indices()
        if not self._covers(A):
            self._analyse(A)
        try:
            self._factor.cholesky_inplace(A)
        except CholmodNotPositiveDefiniteError as error:
            raise np.linalg.LinAlgError(str(error)) from error
        return SimpleNamespace(solve=self._factor.solve_A)

    def _covers(self, A):
        """Whether the analysed pattern holds ``A``'s (sorted CSC) entries."""
        P = self._pattern
        if P is None or A.shape != P.shape:
            return False
        if np.array_equal(A.indptr, P.indptr) and np.array_equal(A.indices, P.indices):
            return True
        return _pattern(A).multiply(P).nnz == A.nnz

    def _analyse(self, A):
        """Analyse ``A``'s pattern with, unless the union has grown too large, the last one's."""
        from sksparse.cholmod import CholmodNotInstalledError

        analyze = _cholmod_analyze()
        pattern = _pattern(A)
        if self._pattern is not None and self._pattern.shape == A.shape:
            union = _pattern(pattern + self._pattern)
            pattern = union if union.nnz <= PATTERN_GROWTH * pattern.nnz else pattern
        try:
            self._factor = analyze(pattern, mode="supernodal", ordering_method="metis")
        except CholmodNotInstalledError:  # a CHOLMOD built without METIS: its own AMD
            self._factor = analyze(pattern, mode="supernodal", ordering_method="amd")
        self._pattern, self.analyses = pattern, self.analyses + 1


PATTERN_GROWTH = 1.5
"""Most entries of an analysed pattern relative to the new matrix's pattern (:class:`CholeskySequence`): beyond, the
old entries are dropped (their fill would cost each factorization more than a new analysis)."""


def _pattern(A):
    """The sparsity pattern of ``A`` (n, n) sparse as a CSC matrix of int8 ones with sorted indices (stored zeros
    included)."""
    A = sp.csc_matrix(A)
    P = sp.csc_matrix((np.ones(len(A.indices), dtype=np.int8), A.indices.copy(), A.indptr.copy()), shape=A.shape)
    P.sum_duplicates()
    P.data[:] = 1
    return P


@functools.cache
def _cholmod_analyze():
    """scikit-sparse's ``cholmod.analyze``, or None (and a warning, once per process) when it is not installed.

    The BLAS and OpenMP that CHOLMOD loads get the thread limit in force (a stage's ``--threads``, one per
    worker process), which ``threadpoolctl`` set on the libraries loaded before them."""
    limit = min((info["num_threads"] for info in threadpool_info()), default=None)
    try:
        from sksparse.cholmod import analyze
    except ImportError:
        log.warning("WARNING: scikit-sparse (CHOLMOD) is not installed: SuperLU factorizes the large systems, "
                    "slower (`make` installs it)")
        return None
    threadpool_limits(limits=limit)
    return analyze


def _superlu_cholesky(A, order):
    """SuperLU's symmetric factorization of ``A`` (n, n) in the elimination ``order`` (n,), as ``.solve(b)``;
    numpy.linalg.LinAlgError when ``A`` is exactly singular."""
    try:
        lu = factorized(A[order][:, order], "NATURAL", symmetric=True)
    except RuntimeError as error:
        raise np.linalg.LinAlgError(str(error)) from error

    def solve(b):
        x = np.empty_like(b, dtype=np.float64)
        x[order] = lu.solve(np.ascontiguousarray(b[order], dtype=np.float64))
        return x

    return SimpleNamespace(solve=solve)


def fill_reducing_order(A, ordering="MMD_AT_PLUS_A"):
    """An elimination order of a symmetric sparsity pattern, for factorizing matrices of that pattern again and again.

    The order depends on the pattern only: ``factorized(B[p][:, p], "NATURAL", symmetric=True)`` of any
    symmetric positive definite ``B`` with ``A``'s pattern has the fill of ``factorized(B, ordering, True)``,
    without computing the ordering each time.

    Parameters
    ----------
    A : (n, n) scipy.sparse matrix
        Symmetric pattern (its values are ignored).
    ordering : str
        SuperLU's fill-reducing ordering (see :func:`factorized`).

    Returns
    -------
    (n,) int64
        ``p``: row and column ``p[i]`` of ``A`` is eliminated i-th.

    Examples
    --------
    >>> import scipy.sparse as sp
    >>> arrow = sp.lil_matrix((4, 4)); arrow[0, :] = arrow[:, 0] = 1.0; arrow.setdiag(1.0)
    >>> int(fill_reducing_order(arrow)[-1])  # the dense row and column last: no fill
    0
    """
    pattern = (sp.csc_matrix(A) != 0).astype(float)
    pattern.setdiag(np.asarray(pattern.sum(axis=0)).ravel() + 1.0)  # diagonally dominant: no breakdown
    return np.argsort(factorized(pattern, ordering, symmetric=True).perm_c).astype(np.int64)
