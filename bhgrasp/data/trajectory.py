"""Trajectory: the time-indexed record of a run, plain arrays that save to and load from ``.npz`` (no pickle).

Units SI, angles in radians, world frame; contacts stored flat with per-sample offsets.
"""

from __future__ import annotations

import itertools
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import pinocchio as pin

from bhgrasp.errors import InputError

_ARRAYS = (
    "t",
    "q",
    "v",
    "u",
    "tau",
    "modes",
    "object_position",
    "object_quaternion",
    "object_twist",
    "contact_offsets",
    "contact_pair",
    "contact_point",
    "contact_normal",
    "contact_depth",
    "contact_force",
    "contact_sticking",
)


@dataclass
class Trajectory:
    """Time-indexed record of a run (N samples; contacts stored flat with per-sample offsets).

    Attributes:
        t: (N,) times [s].
        q, v: (N, nv_hand) hand joint positions [rad] and velocities [rad/s].
        u: (N, n_inputs) control inputs held over each sample (zero-order hold).
        tau: (N, nv_hand) joint torques the actuators delivered [N m] (inputs plus coupling reactions).
        modes: (N, n_modes) actuation modes (e.g. TorqueSwitch broken per finger).
        object_position: (N, n_objects, 3) [m]; object_quaternion: (N, n_objects, 4) as (x, y, z, w);
        object_twist: (N, n_objects, 6) world-aligned.
        contact_offsets: (N + 1,) contacts of sample k are rows ``contact_offsets[k]:contact_offsets[k + 1]``.
        contact_pair, contact_point, contact_normal, contact_depth, contact_force, contact_sticking: flat
            per-contact arrays (pair index, [m], unit, [m], force on body b [N], bool).
        log: Controller internals, name -> (N, ...) array; NaN in the samples where the controller did not log
            that name (e.g. a grasp controller's keys before a supervisor starts it).
        joint_names, object_names: Labels; pair_bodies: (n_pairs, 2) body names of each collision pair.
    """

    t: np.ndarray
    q: np.ndarray
    v: np.ndarray
    u: np.ndarray
    tau: np.ndarray
    modes: np.ndarray
    object_position: np.ndarray
    object_quaternion: np.ndarray
    object_twist: np.ndarray
    contact_offsets: np.ndarray
    contact_pair: np.ndarray
    contact_point: np.ndarray
    contact_normal: np.ndarray
    contact_depth: np.ndarray
    contact_force: np.ndarray
    contact_sticking: np.ndarray
    log: dict[str, np.ndarray] = field(default_factory=dict)
    joint_names: tuple[str, ...] = ()
    object_names: tuple[str, ...] = ()
    pair_bodies: np.ndarray = field(default_factory=lambda: np.zeros((0, 2), dtype=str))

    def __len__(self) -> int:
        return len(self.t)

    def __repr__(self) -> str:
        span = f"{self.t[0]:.4g}..{self.t[-1]:.4g} s" if len(self) else "empty"
        return (
            f"Trajectory({len(self)} samples, {span}, joints={len(self.joint_names)}, "
            f"objects={list(self.object_names)}, contacts={len(self.contact_pair)}, log={sorted(self.log)})"
        )

    # ------------------------------------------------------------------ contacts
    def contacts_at(self, k: int) -> dict[str, np.ndarray]:
        """The contacts of sample ``k`` as arrays (pair, point, normal, depth, force, sticking, bodies)."""
        rows = slice(self.contact_offsets[k], self.contact_offsets[k + 1])
        pair = self.contact_pair[rows]
        return {
            "pair": pair,
            "point": self.contact_point[rows],
            "normal": self.contact_normal[rows],
            "depth": self.contact_depth[rows],
            "force": self.contact_force[rows],
            "sticking": self.contact_sticking[rows],
            "bodies": self.pair_bodies[pair] if len(self.pair_bodies) else np.zeros((len(pair), 2), dtype=str),
        }

    def contact_count(self) -> np.ndarray:
        """(N,) number of contact points per sample."""
        return np.diff(self.contact_offsets)

    def object_euler_zyz(self) -> np.ndarray:
        """(N, n_objects, 3) object orientations as the thesis' Z-Y-Z Euler angles [rad] (for reporting only)."""
        from bhgrasp.model.orientation import zyz_from_rotation

        n, m = self.object_quaternion.shape[:2]
        angles = np.empty((n, m, 3))
        for k in range(n):
            for i in range(m):
                rotation = pin.Quaternion(*np.roll(self.object_quaternion[k, i], 1)).toRotationMatrix()
                angles[k, i] = zyz_from_rotation(rotation)
        return angles

    def max_penetration(self) -> float:
        """Deepest contact of the whole run [m]."""
        return float(self.contact_depth.max()) if len(self.contact_depth) else 0.0

    # ------------------------------------------------------------------ slicing
    def between(self, start: float, stop: float) -> Trajectory:
        """Samples with ``start <= t <= stop`` [s]."""
        slack = 1e-9 * max(1.0, abs(start), abs(stop))  # times are k dt: do not lose a sample to rounding
        indices = np.flatnonzero((self.t >= start - slack) & (self.t <= stop + slack))
        if len(indices) == 0:
            raise InputError(f"no samples between t = {start} and {stop} s (run spans {self.t[0]}..{self.t[-1]} s)")
        return self[int(indices[0]) : int(indices[-1]) + 1]

    def __getitem__(self, index: slice) -> Trajectory:
        if not isinstance(index, slice) or index.step not in (None, 1):
            raise InputError(f"a Trajectory is sliced by a contiguous slice, got {index!r}")
        start, stop, _ = index.indices(len(self))
        rows = slice(int(self.contact_offsets[start]), int(self.contact_offsets[stop]))
        offsets = self.contact_offsets[start : stop + 1] - self.contact_offsets[start]
        sample = {name: getattr(self, name)[start:stop] for name in _ARRAYS if not name.startswith("contact_")}
        contacts = {name: getattr(self, name)[rows] for name in _ARRAYS if name.startswith("contact_")}
        contacts["contact_offsets"] = offsets
        log = {name: values[start:stop] for name, values in self.log.items()}
        return Trajectory(
            **sample,
            **contacts,
            log=log,
            joint_names=self.joint_names,
            object_names=self.object_names,
            pair_bodies=self.pair_bodies,
        )

    @classmethod
    def joined(cls, parts: list[Trajectory]) -> Trajectory:
        """One record of ``parts`` in order (runs of one scene whose times increase from part to part).

        Empty parts are skipped; a log name missing from a part is NaN in its samples.

        Raises:
            InputError: No samples, parts of different scenes (labels or array widths), or times that do not
                increase across a junction.
        """
        parts = [part[0 : len(part)] for part in parts if len(part)]  # slices: contacts from row 0, logs per sample
        if not parts:
            raise InputError("joining trajectories needs at least one sample, got none")
        first = parts[0]
        for part in parts[1:]:
            same = part.joint_names == first.joint_names and part.object_names == first.object_names
            same = same and np.array_equal(part.pair_bodies, first.pair_bodies)
            widths = all(getattr(part, n).shape[1:] == getattr(first, n).shape[1:] for n in _ARRAYS)
            logs = all(part.log[n].shape[1:] == first.log[n].shape[1:] for n in part.log.keys() & first.log.keys())
            if not (same and widths and logs):
                raise InputError("joined trajectories must record one scene (the same joints, objects and pairs)")
        for before, after in itertools.pairwise(parts):
            if not after.t[0] > before.t[-1]:
                raise InputError(
                    f"joined trajectories' times must increase: a part ends at t = {before.t[-1]:.6g} s and the next "
                    f"starts at {after.t[0]:.6g} s"
                )
        arrays = {name: np.concatenate([getattr(p, name) for p in parts]) for name in _ARRAYS}
        ends = np.cumsum([0] + [int(p.contact_offsets[-1]) for p in parts[:-1]])
        arrays["contact_offsets"] = np.concatenate(
            [first.contact_offsets[:1], *(p.contact_offsets[1:] + end for p, end in zip(parts, ends))]
        )
        log = {}
        for name in dict.fromkeys(name for p in parts for name in p.log):
            shape = next(p.log[name].shape[1:] for p in parts if name in p.log)
            log[name] = np.concatenate(
                [p.log[name] if name in p.log else np.full((len(p), *shape), np.nan) for p in parts]
            )
        return cls(
            **arrays,
            log=log,
            joint_names=first.joint_names,
            object_names=first.object_names,
            pair_bodies=first.pair_bodies,
        )

    # ------------------------------------------------------------------ files
    def save(self, path: str | Path) -> Path:
        """Write an ``.npz`` file (plain arrays, no pickle)."""
        path = Path(path)
        arrays = {name: getattr(self, name) for name in _ARRAYS}
        arrays.update({f"log/{name}": values for name, values in self.log.items()})
        arrays["joint_names"] = np.array(self.joint_names, dtype=str)
        arrays["object_names"] = np.array(self.object_names, dtype=str)
        arrays["pair_bodies"] = np.asarray(self.pair_bodies, dtype=str)
        np.savez_compressed(path, **arrays)
        return path if path.suffix == ".npz" else path.with_suffix(path.suffix + ".npz")

    @classmethod
    def load(cls, path: str | Path) -> Trajectory:
        """Read a file written by :meth:`save` (``allow_pickle=False``: untrusted files cannot run code).

        Raises:
            InputError: The file is missing, is not an ``.npz`` archive, or holds pickled objects or other arrays.
        """
        path = Path(path)
        if not path.is_file():
            raise InputError(f"no trajectory file at {str(path)!r} (expected an .npz written by Trajectory.save)")
        try:
            data = np.load(path, allow_pickle=False)
        except (ValueError, OSError, EOFError) as error:  # raw pickles and other files: refused unread
            raise InputError(
                f"{str(path)!r} is not a bhgrasp trajectory (.npz of plain arrays written by Trajectory.save): {error}"
            ) from error
        if not isinstance(data, np.lib.npyio.NpzFile):
            raise InputError(
                f"{str(path)!r} is not a bhgrasp trajectory: a single .npy array, expected an .npz archive"
            )
        with data:
            missing = [name for name in _ARRAYS if name not in data.files]
            if missing:
                raise InputError(f"{str(path)!r} is not a bhgrasp trajectory: missing arrays {missing}")
            try:
                arrays = {name: data[name] for name in _ARRAYS}
                log = {name[4:]: data[name] for name in data.files if name.startswith("log/")}
                names = (data["joint_names"], data["object_names"], data["pair_bodies"])
            except ValueError as error:  # an object array would need pickle: never unpickled
                raise InputError(
                    f"{str(path)!r} holds pickled objects, which are never loaded (untrusted code): {error}"
                ) from error
            return cls(
                **arrays,
                log=log,
                joint_names=tuple(str(n) for n in names[0]),
                object_names=tuple(str(n) for n in names[1]),
                pair_bodies=names[2],
            )


__all__ = ["Trajectory"]
