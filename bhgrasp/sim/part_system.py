"""The implicit step's velocity system for scenes of many parts, assembled sparse and solved by a sparse factorisation.

The implicit step (:mod:`~bhgrasp.sim.python_engine`) solves, in the driven coordinates ``w`` (``v+ = T w``)::

    T^T (A + dt sum_i J_i^T G_i J_i) T w = T^T b,     A = M + dt diag(dt K + C)

As one dense matrix this costs O(nv^2) memory and O(nv^3) work a pass, and each contact's ``J^T G J`` O(nv^2): a pile
of 64 objects (nv = 384) stepped ~100x slower than MuJoCo.  But the scene's parts (:mod:`~bhgrasp.sim.scene_parts`:
the hand's joints, each object's) share no inertia, so ``A`` is block diagonal, and a contact's Jacobian is non-zero
only on the columns of the one or two parts it touches.  :class:`PartSystem` keeps that structure: ``A`` from the
parts' blocks, each contact's ``J^T G J`` as at most four blocks, ``T`` as the hand's transmission beside an identity,
and a sparse factorisation whose fill follows the contact graph.  Work and memory grow with the parts and the contacts.

The compiled twin is ``src/part_system.{hpp,cpp}``: there the factorisation is a sparse Cholesky (Eigen's
``SimplicialLLT``, AMD ordering), here SuperLU (``scipy.sparse.linalg.splu``), so the two agree to round-off, not to the
bit.  The solution is the dense solve's to round-off as well (tests/test_part_system.py); which a simulator uses is
:attr:`~bhgrasp.sim.settings.SimulatorSettings.linear_solver`.
"""

from __future__ import annotations

import numpy as np
import scipy.sparse as sparse
from scipy.sparse.linalg import splu


def block_diagonal(blocks: list[np.ndarray]) -> sparse.csr_array:
    """The (n, n) block-diagonal matrix of square ``blocks``, in their order (sparse)."""
    return sparse.csr_array(sparse.block_diag(blocks, format="csr"))


def gain_blocks(gains: np.ndarray) -> sparse.bsr_array:
    """The (3m, 3m) block-diagonal matrix of the contacts' 3x3 gains ``gains`` (m, 3, 3)."""
    m = len(gains)
    return sparse.bsr_array((gains, np.arange(m), np.arange(m + 1)), shape=(3 * m, 3 * m))


class PartSystem:
    """One step's velocity system by parts: :meth:`begin` with the parts' blocks, then a :meth:`solve` per pass."""

    def __init__(self) -> None:
        """An empty system (:meth:`begin` sets it up)."""
        self.transmission: sparse.csr_array | None = None  # T: the hand's transmission beside an identity
        self.system: sparse.sparray | None = None  # A

    def begin(self, hand_transmission: np.ndarray, system: sparse.sparray) -> None:
        """The step's hand transmission ``T`` (nv_hand, n_driven) and ``A`` (nv, nv, sparse, block diagonal)."""
        objects = system.shape[0] - hand_transmission.shape[0]
        self.transmission = sparse.csr_array(
            sparse.block_diag((sparse.csr_array(hand_transmission), sparse.identity(objects)), format="csr")
        )
        self.system = system

    def solve(self, stacked: sparse.sparray | None, gains: np.ndarray, scale: float, rhs: np.ndarray) -> np.ndarray:
        """``v+`` (nv,) of the system with the contacts' stacked Jacobians and gains, right side ``b`` (nv,).

        ``stacked`` (3m, nv), sparse (None: ``A`` alone); ``gains`` (m, 3, 3), scaled by ``scale``.
        """
        matrix = self.system
        if stacked is not None:
            matrix = matrix + scale * (stacked.T @ (gain_blocks(gains) @ stacked))
        transmission = self.transmission
        reduced = sparse.csc_array(transmission.T @ matrix @ transmission)
        return transmission @ splu(reduced).solve(transmission.T @ rhs)


__all__ = ["PartSystem", "block_diagonal", "gain_blocks"]
