"""Convex decomposition of a non-convex mesh with CoACD, cached on disk by the mesh's hash.

A non-convex body (a mug, a bowl, an L-shaped tool) collides as several convex pieces: CoACD (Wei et al., "Approximate
convex decomposition for 3D meshes with collision-aware concavity and tree search", SIGGRAPH 2022; the ``coacd``
package) cuts the mesh until every piece is within ``concavity`` of its hull, and each piece collides as its hull.
CoACD runs on one OpenMP thread here: on several its pieces differ in their last bits from run to run (a mug cut
twice: the same 32 pieces' sizes, different hashes); on one, the same mesh and settings give the same pieces, bit for
bit (checked between two fresh installs).  It takes seconds (1-2 s for the banana and the drill, 7-11 s for the
household mug and bowl), so the pieces are kept in ``cache_dir()`` under the
SHA-256 of the mesh and the settings, as ``.npz`` files read without pickle; the pieces of
:mod:`~bhgrasp.model.household_objects`'s objects ship with the package (:data:`SHIPPED`, written by
:func:`~bhgrasp.model.household_objects.write_shipped_pieces`).
"""

from __future__ import annotations

import ctypes
import hashlib
import os
import tempfile
import warnings
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
            try:
                return read_pieces(path)
            except (OSError, ValueError, KeyError) as error:  # a damaged file: cut again (and replace it)
                warnings.warn(f"decomposition {path} is unreadable ({error}); cutting the mesh again", stacklevel=2)
    pieces = _decompose(np.asarray(vertices, dtype=np.float64), np.asarray(faces, dtype=np.int32), concavity)
    try:
        write_pieces(cache_dir() / name, pieces)
    except OSError as error:  # a read-only home: the pieces are still good, only not kept
        warnings.warn(f"could not keep the decomposition in {cache_dir()} ({error}); set {CACHE_ENV}", stacklevel=2)
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
    """The pieces stored in ``path`` (no pickle).

    Raises:
        ValueError: The file holds no pieces, or a piece that is not (n >= 4, 3) finite points.
    """
    with np.load(path, allow_pickle=False) as stored:
        pieces = [np.array(stored[f"piece{k}"], dtype=np.float64) for k in range(int(stored["count"]))]
    for piece in pieces:
        if piece.ndim != 2 or piece.shape[1] != 3 or len(piece) < 4 or not np.all(np.isfinite(piece)):
            raise ValueError(f"a piece of shape {piece.shape} (or not finite)")
    if not pieces:
        raise ValueError("no pieces")
    return pieces


def write_pieces(path: Path, pieces: list[np.ndarray]) -> None:
    """Store ``pieces`` in ``path`` (atomic: a parallel run reads a whole file or none)."""
    path.parent.mkdir(parents=True, exist_ok=True)
    handle, partial = tempfile.mkstemp(suffix=".npz", prefix=f"{path.stem}.", dir=path.parent)  # one per writer
    arrays = {f"piece{k}": piece for k, piece in enumerate(pieces)}
    with os.fdopen(handle, "wb") as file:
        np.savez_compressed(file, count=len(pieces), made_by=f"coacd {_coacd_version()}", **arrays)
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
    """Set CoACD's own OpenMP runtime (the libgomp its Linux wheel ships) to one thread for this thread's next regions.

    Where there is none to be found (another platform's wheel, a source build), warn that the pieces may differ from
    run to run.
    """
    libraries = sorted((package.parent / "coacd.libs").glob("libgomp*.so*"))
    for library in libraries:
        ctypes.CDLL(str(library)).omp_set_num_threads(1)
    if not libraries:
        warnings.warn(
            "CoACD's OpenMP runtime was not found: it may cut on several threads, and then not give the same pieces "
            "twice (run with OMP_NUM_THREADS=1 for that)",
            stacklevel=3,
        )
