"""Convex decomposition of a non-convex mesh with CoACD, cached on disk by the mesh's hash.

A non-convex body (a mug, a bowl, an L-shaped tool) collides as several convex pieces: CoACD (Wei et al., "Approximate
convex decomposition for 3D meshes with collision-aware concavity and tree search", SIGGRAPH 2022; the ``coacd``
package) cuts the mesh until every piece is within ``concavity`` of its hull, and each piece collides as its hull.
CoACD runs on one OpenMP thread here: on several its pieces differ in their last bits from run to run (a mug's 32
pieces, same sizes, different hashes); on one, the same mesh and settings give the same pieces, bit for bit.  It
takes seconds (7-11 s for the household mug and bowl), so the pieces are kept in ``cache_dir()`` under the
SHA-256 of the mesh and the settings, as ``.npz`` files read without pickle; the pieces of
:mod:`~bhgrasp.model.household`'s objects ship with the package (:data:`SHIPPED`, written by
:func:`~bhgrasp.model.household.write_shipped_pieces`).
"""

from __future__ import annotations

import ctypes
import hashlib
import os
from importlib import metadata
from pathlib import Path

import numpy as np

from bhgrasp._validation import as_positive
from bhgrasp.errors import InputError

SEED = 0  # CoACD's tree search is seeded: the same seed, the same pieces
CACHE_ENV = "BHGRASP_CACHE_DIR"
SHIPPED = Path(__file__).with_name("household_pieces")  # decompositions made once and shipped, same file names

__all__ = [
    "CACHE_ENV",
    "SHIPPED",
    "cache_dir",
    "convex_pieces",
    "decomposition_key",
    "read_pieces",
    "write_pieces",
]


def cache_dir() -> Path:
    """Where decompositions are kept: ``$BHGRASP_CACHE_DIR/decompositions`` or ``~/.cache/bhgrasp/decompositions``."""
    root = os.environ.get(CACHE_ENV) or os.path.join(os.path.expanduser("~"), ".cache", "bhgrasp")
    return Path(root) / "decompositions"


def convex_pieces(
    vertices: np.ndarray, faces: np.ndarray, concavity: float = 0.05, source: tuple | None = None
) -> list[np.ndarray]:
    """The vertices of each convex piece of a closed mesh, (n_k, 3) arrays in the mesh's frame [m].

    Args:
        vertices: (n, 3) vertex positions [m].
        faces: (m, 3) vertex indexes of each triangle.
        concavity: CoACD's threshold: the largest concavity a piece may keep, relative to the mesh's size (0.05 is
            CoACD's default; smaller gives more, finer pieces).
        source: ``(vertices, faces, scale)`` as the user gave them, which name the pieces on disk (default
            ``(vertices, faces, 1.0)``): :class:`~bhgrasp.model.mesh_object.Mesh` decomposes its body-frame vertices,
            whose last bits may differ between machines (its centre of mass is a sum), and names them by its input.
    """
    concavity = as_positive(concavity, "concavity")
    source = (vertices, faces, 1.0) if source is None else source
    name = f"{decomposition_key(*source, concavity)}.npz"
    for path in (SHIPPED / name, cache_dir() / name):
        if path.is_file():
            return read_pieces(path)
    pieces = _decompose(np.asarray(vertices, dtype=np.float64), np.asarray(faces, dtype=np.int32), concavity)
    write_pieces(cache_dir() / name, pieces)
    return pieces


def decomposition_key(vertices: np.ndarray, faces: np.ndarray, scale: float, concavity: float) -> str:
    """The SHA-256 (hex) of a mesh, its scale and the settings: the name of its pieces' file.

    Not CoACD's version: pieces once made stay the body's collision shape (a file records the version that made it),
    so an upgrade changes no simulation and the shipped pieces are found whatever CoACD is installed.
    """
    digest = hashlib.sha256(np.ascontiguousarray(vertices, dtype=np.float64).tobytes())
    digest.update(np.ascontiguousarray(faces, dtype=np.int64).tobytes())
    digest.update(f"scale {float(scale)!r} concavity {float(concavity)!r} seed {SEED} no remeshing".encode())
    return digest.hexdigest()


def read_pieces(path: Path) -> list[np.ndarray]:
    """The pieces stored in ``path`` (no pickle)."""
    with np.load(path, allow_pickle=False) as stored:
        return [np.array(stored[f"piece{k}"], dtype=np.float64) for k in range(int(stored["count"]))]


def write_pieces(path: Path, pieces: list[np.ndarray]) -> None:
    """Store ``pieces`` in ``path`` (atomic: a parallel run reads a whole file or none)."""
    path.parent.mkdir(parents=True, exist_ok=True)
    partial = path.with_name(f"{path.stem}.{os.getpid()}.tmp.npz")
    arrays = {f"piece{k}": piece for k, piece in enumerate(pieces)}
    np.savez_compressed(partial, count=len(pieces), made_by=f"coacd {_coacd_version()}", **arrays)
    os.replace(partial, path)


def _coacd_version() -> str:
    try:
        return metadata.version("coacd")
    except metadata.PackageNotFoundError:
        return "unknown"


def _decompose(vertices: np.ndarray, faces: np.ndarray, concavity: float) -> list[np.ndarray]:
    try:
        import coacd
    except ImportError as error:
        raise InputError("a decomposed mesh needs the `coacd` package (pip install coacd)") from error
    coacd.set_log_level("error")
    _one_openmp_thread(Path(coacd.__file__).parent)
    # No remeshing: Mesh hands over closed, consistently wound surfaces only.  CoACD's "auto" remeshed the drill
    # (it judged it non-manifold) and a piece stood 1.47 mm outside the surface; without, 0.004 mm, in 1.6 s, not 12 s.
    parts = coacd.run_coacd(coacd.Mesh(vertices, faces), threshold=concavity, seed=SEED, preprocess_mode="off")
    pieces = [np.array(part_vertices, dtype=np.float64) for part_vertices, _ in parts]
    return sorted(pieces, key=lambda piece: tuple(piece.mean(axis=0)))  # an order independent of CoACD's


def _one_openmp_thread(package: Path) -> None:
    """Set CoACD's own OpenMP runtime (the libgomp its wheel ships) to one thread for this thread's next regions."""
    libraries = sorted((package.parent / "coacd.libs").glob("libgomp*.so*"))
    for library in libraries:
        ctypes.CDLL(str(library)).omp_set_num_threads(1)
