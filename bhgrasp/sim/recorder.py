"""Recorder: collects a simulation run's samples (one by one, or a compiled loop's at once) into a Trajectory."""

from __future__ import annotations

from typing import Any

import numpy as np
import pinocchio as pin

from bhgrasp._native import default_core
from bhgrasp.data import State, Trajectory
from bhgrasp.errors import InputError
from bhgrasp.sim.actuation import Actuation
from bhgrasp.sim.scene import Scene

_FLOAT = np.dtype(float)  # the native float64 of a logged array that is copied as it is


class Recorder:
    """Collects a run's samples (:meth:`add`, :meth:`add_run`) and assembles the :class:`~bhgrasp.data.Trajectory`.

    A sample keeps references to what the step made (the scene's q and v, the input, the drive torques, the
    contacts as the engine returned them); the arrays of the trajectory are assembled once, at the end.
    """

    _CONTACT_FIELDS = ("pair", "point", "normal", "depth", "force", "sticking")

    def __init__(self, scene: Scene, actuation: Actuation, samples: int = 1024) -> None:
        """Record ``scene`` driven through ``actuation`` (for its mode flags).

        ``samples``: the run's expected count of samples (the log's columns start that long, double when full).
        """
        self.scene, self.actuation = scene, actuation
        self.t, self.scene_q, self.scene_v = [], [], []
        self.u, self.tau, self.modes = [], [], []
        self.contacts, self.counts = [], []  # the contacts as the engine returned them (those with rows); rows a sample
        self.log = LogColumns(max(int(samples), 1))

    def add(self, state: State, u: np.ndarray, info: Any, log: Any) -> None:
        """Append one sample: state, held input, the step's contacts and drive torques, controller internals.

        ``u`` and ``info``'s arrays are kept, not copied: the simulator makes new ones at every step.
        """
        self.t.append(state.t)
        self.scene_q.append(state.scene_q)
        self.scene_v.append(state.scene_v)
        self.u.append(u)
        self.tau.append(info.drive_torques)
        modes = state.actuation_modes
        self.modes.append(self.actuation.modes() if modes is None else modes)
        self._add_contacts(info.contact_arrays)
        if isinstance(log, dict):
            self.log.add(log, len(self.t) - 1)

    def add_run(self, state: State, info: Any, run: Any, log: dict[str, np.ndarray]) -> None:
        """Append the samples of a compiled closed loop's ``run`` (``bhgrasp._core.LoopRun``) that began at ``state``.

        Sample i is the state before the run's step i: ``state`` (with ``info``, the step that made it) for the
        first, the run's rows after that; the inputs are the run's.  ``log``: each controller log entry's rows, one
        per sample (:meth:`LogColumns.add_rows`).  The run's arrays are kept, not copied.
        """
        n = int(run.steps)
        if n < 1:
            raise InputError(f"a compiled run's samples are recorded once it took a step, got {n} steps")
        first = len(self.t)
        self.t.append(state.t)
        self.t.extend(run.t[: n - 1].tolist())
        self.scene_q.append(state.scene_q)
        self.scene_q.extend(run.q[: n - 1])
        self.scene_v.append(state.scene_v)
        self.scene_v.extend(run.v[: n - 1])
        self.u.extend(run.u)
        self.tau.append(info.drive_torques)
        self.tau.extend(run.drive[: n - 1])
        modes = state.actuation_modes  # (a compiled loop runs an actuation without modes)
        self.modes.extend([self.actuation.modes() if modes is None else modes] * n)
        self._add_contacts(info.contact_arrays)
        self.counts.extend(run.counts.tolist())
        if len(run.contacts):
            self.contacts.append(run.contacts)
        self.log.add_rows(log, first)

    def _add_contacts(self, contacts: Any) -> None:
        """One sample's contacts as the engine returned them (kept only if it has rows)."""
        count = len(contacts)
        self.counts.append(count)
        if count:
            self.contacts.append(contacts)

    def _objects(self, scene_q: np.ndarray, scene_v: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """(N, n_objects, 3) COM positions [m], (N, n_objects, 4) quaternions (x, y, z, w), (N, n_objects, 6) twists.

        A free object's are read from the scene's coordinates (position and unit quaternion of its COM frame;
        world-aligned linear and body angular velocity, turned to world); a spring-mounted object slides along its
        direction with a fixed orientation.
        """
        scene = self.scene
        n, n_obj = len(scene_q), len(scene.objects)
        position, quaternion, twist = np.zeros((n, n_obj, 3)), np.zeros((n, n_obj, 4)), np.zeros((n, n_obj, 6))
        for i, item in enumerate(scene.objects):
            q, v = scene_q[:, scene.object_q_slice(i)], scene_v[:, scene.object_v_slice(i)]
            if q.shape[1] == 7:
                position[:, i], quaternion[:, i] = q[:, :3], q[:, 3:]
                twist[:, i, :3], twist[:, i, 3:] = v[:, :3], _rotate(q[:, 3:], v[:, 3:])
            else:
                position[:, i] = item.pose.translation + q[:, :1] * item.direction
                quaternion[:, i] = pin.SE3ToXYZQUAT(item.pose)[3:]
                twist[:, i, :3] = v[:, :1] * item.direction
        return position, quaternion, twist

    def _contact_arrays(self, parts: list) -> dict[str, np.ndarray]:
        """The recorded contacts' arrays (:attr:`_CONTACT_FIELDS`), one sample's rows after the other.

        A compiled run's contacts are joined in C++ (one call instead of six array reads per sample).
        """
        core = default_core()
        if core is not None and parts and all(isinstance(part, core.Contacts) for part in parts):
            parts = [core.concatenate(parts)]
        arrays = {}
        for name, shape, kind in zip(
            self._CONTACT_FIELDS,
            ((-1,), (-1, 3), (-1, 3), (-1,), (-1, 3), (-1,)),
            (int, float, float, float, float, bool),
        ):
            values = [getattr(part, name) for part in parts]
            arrays[name] = (np.concatenate(values) if values else np.zeros(0)).astype(kind).reshape(shape)
        return arrays

    def trajectory(self) -> Trajectory:
        """The recorded run."""
        scene = self.scene
        n = len(self.t)
        scene_q = np.array(self.scene_q).reshape(n, scene.nq)
        scene_v = np.array(self.scene_v).reshape(n, scene.nv)
        position, quaternion, twist = self._objects(scene_q, scene_v)
        counts = self.counts
        arrays = self._contact_arrays(self.contacts)
        return Trajectory(
            t=np.array(self.t),
            q=scene_q[:, : scene.nq_hand].copy(),
            v=scene_v[:, : scene.nv_hand].copy(),
            u=np.array(self.u).reshape(n, -1),
            tau=np.array(self.tau).reshape(n, -1),
            modes=np.array(self.modes).reshape(n, -1),
            object_position=position,
            object_quaternion=quaternion,
            object_twist=twist,
            contact_offsets=np.concatenate(([0], np.cumsum(counts))).astype(int),
            contact_pair=arrays["pair"],
            contact_point=arrays["point"],
            contact_normal=arrays["normal"],
            contact_depth=arrays["depth"],
            contact_force=arrays["force"],
            contact_sticking=arrays["sticking"],
            log=self.log.arrays(),
            joint_names=scene.hand.joint_names,
            object_names=tuple(scene.object_names),
            pair_bodies=np.array([(p.body_a, p.body_b) for p in scene.pairs], dtype=str).reshape(-1, 2),
        )


def _rotate(quaternions: np.ndarray, vectors: np.ndarray) -> np.ndarray:
    """R(q) x for rows of unit quaternions (x, y, z, w) and vectors (N, 3): x + 2 w (u x x) + 2 u x (u x x)."""
    axis, scalar = quaternions[:, :3], quaternions[:, 3:]
    turned = 2.0 * np.cross(axis, vectors)
    return vectors + scalar * turned + np.cross(axis, turned)


class LogColumns:
    """A run's controller log, one preallocated column per entry: sample k's value written into row k.

    Every entry is recorded as ``np.array(value, dtype=float)`` would make it, rows of one shape per entry; a sample
    without an entry (before it first appears, or a skipped sample) holds NaN, so every entry has one row per sample
    up to the last that logged.  A sample with the last one's entries is written in place, with no array made per
    entry when they are float64 arrays (a copy per entry and sample, and stacking them at the end, cost the grasp demo
    ~15 us a step).
    """

    _NOT_NUMBERS = (TypeError, ValueError, OverflowError)

    def __init__(self, capacity: int) -> None:
        """Columns of ``capacity`` rows to start with (doubled when a sample does not fit)."""
        self._columns: dict[str, np.ndarray] = {}  # entry -> (capacity, *shape) float64, in order of first appearance
        self._shapes: dict[str, tuple[int, ...]] = {}
        self._capacity, self._logged = capacity, 0  # rows allocated; samples every column holds (NaN where absent)

    def add(self, log: dict, sample: int) -> None:
        """Record ``log`` (entry -> number or array) as sample ``sample`` (samples logged before it and skipped: NaN).

        Raises:
            InputError: An entry that is not numbers or whose shape differs from its earlier samples' (nothing of the
                sample is recorded), or a sample before one already recorded.
        """
        if sample < self._logged:
            raise InputError(f"log sample {sample} after sample {self._logged - 1}: samples are recorded in order")
        if sample >= self._capacity:
            self._grow(sample + 1)
        columns, shapes = self._columns, self._shapes
        if self._logged == sample and log.keys() == columns.keys():  # the usual sample: the last one's entries
            for name, value in log.items():
                if getattr(value, "dtype", None) is not _FLOAT:
                    try:
                        value = np.asarray(value, dtype=float)
                    except self._NOT_NUMBERS:
                        break  # (the checks below say why)
                if value.shape != shapes[name]:
                    break
                columns[name][sample] = value
            else:
                self._logged = sample + 1
                return
        values = {name: self._checked(name, value, sample) for name, value in log.items()}
        self._write({name: value[None] for name, value in values.items()}, sample, 1)

    def _checked(self, name: str, value: Any, sample: int) -> np.ndarray:
        """``value`` as a float array of entry ``name``'s shape (its first sample's), else an ``InputError``."""
        try:
            array = np.asarray(value, dtype=float)
        except self._NOT_NUMBERS as error:
            raise InputError(f"log entry {name!r} at sample {sample} must be numbers, got {value!r}") from error
        shape = self._shapes.get(name, array.shape)
        if array.shape != shape:
            raise InputError(
                f"log entry {name!r} has shape {array.shape} at sample {sample}, {shape} before: an entry keeps its "
                "shape through a run"
            )
        return array

    def _grow(self, rows: int) -> None:
        """Room for ``rows`` samples at least (twice the capacity), the logged ones copied."""
        capacity = max(rows, 2 * self._capacity)
        for name, column in self._columns.items():
            grown = np.empty((capacity, *column.shape[1:]))
            grown[: self._logged] = column[: self._logged]
            self._columns[name] = grown
        self._capacity = capacity

    def add_rows(self, rows: dict[str, np.ndarray], sample: int) -> None:
        """Record samples ``sample``, ``sample + 1``, ... at once: ``rows`` maps each entry to its ``(n, *shape)`` rows.

        Entries absent from ``rows`` hold NaN in these samples, as :meth:`add`'s.

        Raises:
            InputError: An entry whose rows are not numbers, or not n of its shape (nothing is recorded), or samples
                before one already recorded.
        """
        if sample < self._logged:
            raise InputError(f"log sample {sample} after sample {self._logged - 1}: samples are recorded in order")
        blocks = {name: self._rows_checked(name, value, sample) for name, value in rows.items()}
        counts = {len(block) for block in blocks.values()}
        if len(counts) > 1:
            raise InputError(f"the log's rows from sample {sample} must be as many for every entry, got {counts}")
        n = counts.pop() if counts else 0
        if sample + n > self._capacity:
            self._grow(sample + n)
        self._write(blocks, sample, n)

    def _write(self, blocks: dict[str, np.ndarray], sample: int, n: int) -> None:
        """Checked ``blocks`` (entry -> (n, *shape) rows) as samples ``sample`` .. ``sample + n - 1`` (room made)."""
        columns = self._columns
        for name, block in blocks.items():
            column = columns.get(name)
            if column is None:  # NaN for every earlier sample (the rows after these are written when reached)
                column = columns[name] = np.empty((self._capacity, *block.shape[1:]))
                column[:sample] = np.nan
                self._shapes[name] = block.shape[1:]
            column[self._logged : sample] = np.nan  # samples skipped since the last log
            column[sample : sample + n] = block
        for name, column in columns.items():
            if name not in blocks:
                column[self._logged : sample + n] = np.nan
        self._logged = sample + n

    def _rows_checked(self, name: str, value: Any, sample: int) -> np.ndarray:
        """``value`` as float rows of entry ``name``'s shape (its first sample's), else an ``InputError``."""
        try:
            rows = np.asarray(value, dtype=float)
        except self._NOT_NUMBERS as error:
            raise InputError(f"log entry {name!r} from sample {sample} must be numbers, got {value!r}") from error
        shape = self._shapes.get(name, rows.shape[1:])
        if rows.ndim == 0 or rows.shape[1:] != shape:
            raise InputError(
                f"log entry {name!r} has rows of shape {rows.shape[1:]} from sample {sample}, {shape} before: an "
                "entry keeps its shape through a run"
            )
        return rows

    def arrays(self) -> dict[str, np.ndarray]:
        """Each entry's (samples logged, *shape) array, in the order the entries first appeared."""
        return {name: column[: self._logged].copy() for name, column in self._columns.items()}
