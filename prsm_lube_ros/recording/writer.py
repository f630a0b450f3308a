# Copyright 2026 prsm_lube_ros developers
# SPDX-License-Identifier: Apache-2.0
"""Writing contract recordings (rosbag2) with :mod:`rosbags`, no ROS install needed.

Three storage forms, as CONTRACT.md accepts them:

* ``'mcap'``: a rosbag2 directory (``metadata.yaml`` + ``<name>.mcap``), the default;
* ``'sqlite3'``: a rosbag2 directory with a ``.db3`` file;
* ``'mcap-file'``: a bare ``.mcap`` file, a rosbag2 mcap without ``metadata.yaml`` beside it.

Messages are the contract's topics under a namespace (default ``/prsm``),
serialized with ``typestore.serialize_cdr`` of
:func:`prsm_lube_ros.recording.typestore.contract_typestore`.  The writer takes numpy
arrays per topic, buffers the serialized messages and writes them in order of
log time on :meth:`ContractBagWriter.flush`, so a producer can hand over one
chunk of time after another with flat memory.  Stamps and log times are
integer nanoseconds since the epoch.
"""
from __future__ import annotations

import bisect
from pathlib import Path
import shutil
from typing import Literal, TYPE_CHECKING

import numpy as np
from rosbags.interfaces import Connection
from rosbags.rosbag2 import CompressionFormat, CompressionMode, StoragePlugin, Writer

from ..contract import (AXIAL_LOAD_TOPIC, JOINT_STATE, JOINT_STATES_TOPIC, SCREW_JOINT, TEMPERATURE, TEMPERATURE_TOPIC,
                        topic_name, VIBRATION_BLOCK, VIBRATION_TOPIC, WRENCH_STAMPED)
from ..errors import InputError
from .typestore import contract_typestore

if TYPE_CHECKING:
    from collections.abc import Iterable, Sequence
    from types import TracebackType

    import numpy.typing as npt
    from rosbags.typesys.store import MsgType, Typestore

__all__ = ['ContractBagWriter', 'STORAGE_FORMATS', 'bag_path', 'check_storage']

#: Storage forms :class:`ContractBagWriter` can write.
STORAGE_FORMATS = ('mcap', 'sqlite3', 'mcap-file')


def bag_path(out_dir: str | Path, name: str, storage: str = 'mcap') -> Path:
    """Where a bag called ``name`` goes in ``out_dir``: a directory, or ``name.mcap`` for 'mcap-file'."""
    check_storage(storage)
    out_dir = Path(out_dir)
    return out_dir / f'{name}.mcap' if storage == 'mcap-file' else out_dir / name


def check_storage(storage: str) -> str:
    """Return storage if it is one of :data:`STORAGE_FORMATS`, else raise :class:`InputError`."""
    if storage not in STORAGE_FORMATS:
        raise InputError(f'storage must be one of {", ".join(STORAGE_FORMATS)}, got {storage!r}')
    return storage


class ContractBagWriter:
    """A new contract bag at ``path``; use as a context manager.

    ``storage`` is one of :data:`STORAGE_FORMATS`.  The ``add_*`` methods take
    arrays of header stamps and log times (int ns since the epoch) and buffer
    the serialized messages; :meth:`flush` writes those logged before a time
    in log-time order (call it with the earliest log time any later message can
    have); :meth:`close` writes the rest.  A path that exists already is an
    :class:`InputError`.  Temperature is only registered when first written.
    """

    def __init__(self, path: str | Path, *, storage: str = 'mcap', namespace: str = '/prsm',
                 compression: str | None = None):
        """Open the bag for writing; ``compression='zstd'`` compresses mcap chunks (storage compression)."""
        self.path = Path(path)
        self.storage = check_storage(storage)
        if self.path.exists():
            raise InputError(f'{self.path}: exists already, not overwriting')
        if storage == 'mcap-file':
            if self.path.suffix != '.mcap':
                raise InputError(f'{self.path}: a bare mcap bag must end in .mcap')
            self._bag_dir = self.path.with_name(self.path.stem + '.rosbag2-partial')
            if self._bag_dir.exists():
                raise InputError(f'{self._bag_dir}: exists already (left from an interrupted write?)')
        else:
            self._bag_dir = self.path
        self.path.parent.mkdir(parents=True, exist_ok=True)
        self.namespace = namespace
        self.typestore: Typestore = contract_typestore()
        plugin = StoragePlugin.SQLITE3 if storage == 'sqlite3' else StoragePlugin.MCAP
        self._writer: Writer | None = Writer(self._bag_dir, version=Writer.VERSION_LATEST, storage_plugin=plugin)
        if compression is not None:
            if compression != 'zstd' or storage == 'sqlite3':
                raise InputError(f'{self.path}: compression {compression!r} is not offered for {storage} storage '
                                 '(mcap storage supports zstd)')
            self._writer.set_compression(CompressionMode.STORAGE, CompressionFormat.ZSTD)
        self._writer.open()
        self._connections: dict[str, Connection] = {}
        self._pending: list[tuple[int, int, Connection, memoryview]] = []
        self._sequence = 0
        self.message_counts: dict[str, int] = {}
        types = self.typestore.types
        self._time = types['builtin_interfaces/msg/Time']
        self._header = types['std_msgs/msg/Header']
        self._vibration = types[VIBRATION_BLOCK]
        self._joint_state = types[JOINT_STATE]
        self._wrench_stamped = types[WRENCH_STAMPED]
        self._wrench = types['geometry_msgs/msg/Wrench']
        self._vector = types['geometry_msgs/msg/Vector3']
        self._temperature = types[TEMPERATURE]

    # -- plumbing -------------------------------------------------------------------------------
    def _connection(self, topic: str, msgtype: str) -> Connection:
        name = topic_name(self.namespace or '/', topic)
        if name not in self._connections:
            assert self._writer is not None, 'the bag is closed'
            self._connections[name] = self._writer.add_connection(name, msgtype, typestore=self.typestore)
            self.message_counts[name] = 0
        return self._connections[name]

    def _stamp(self, stamp_ns: int, frame_id: str) -> MsgType:
        seconds, nanoseconds = divmod(int(stamp_ns), 1_000_000_000)
        return self._header(stamp=self._time(sec=seconds, nanosec=nanoseconds), frame_id=frame_id)

    def _queue(self, connection: Connection, log_times: np.ndarray | Sequence[int], messages: Iterable[MsgType],
               msgtype: str) -> None:
        serialize = self.typestore.serialize_cdr
        for log_time, message in zip(np.asarray(log_times, dtype=np.int64).tolist(), messages):
            self._pending.append((log_time, self._sequence, connection, serialize(message, msgtype)))
            self._sequence += 1
        self.message_counts[connection.topic] += len(log_times)

    # -- topics ---------------------------------------------------------------------------------
    def add_vibration(self, stamps_ns: npt.ArrayLike, log_times_ns: np.ndarray | Sequence[int], sample_rate: float,
                      samples: npt.ArrayLike, frame_id: str = '') -> None:
        """``VibrationBlock`` messages: row k of ``samples`` (m/s^2) acquired from ``stamps_ns[k]``."""
        samples = np.asarray(samples, dtype=np.float32)
        connection = self._connection(VIBRATION_TOPIC, VIBRATION_BLOCK)
        messages = (self._vibration(header=self._stamp(stamp, frame_id), sample_rate=float(sample_rate),
                                    samples=np.ascontiguousarray(row))
                    for stamp, row in zip(np.asarray(stamps_ns).tolist(), samples))
        self._queue(connection, log_times_ns, messages, VIBRATION_BLOCK)

    def add_joint_states(self, stamps_ns: npt.ArrayLike, log_times_ns: np.ndarray | Sequence[int],
                         angles: npt.ArrayLike, speeds: npt.ArrayLike) -> None:
        """``JointState`` messages with one entry ``screw``: angle in rad, speed in rad/s."""
        connection = self._connection(JOINT_STATES_TOPIC, JOINT_STATE)
        empty = np.zeros(0, dtype=np.float64)
        messages = (self._joint_state(header=self._stamp(stamp, ''), name=[SCREW_JOINT],
                                      position=np.array([angle]), velocity=np.array([speed]),
                                      effort=empty)
                    for stamp, angle, speed in zip(np.asarray(stamps_ns).tolist(),
                                                   np.asarray(angles, dtype=float).tolist(),
                                                   np.asarray(speeds, dtype=float).tolist()))
        self._queue(connection, log_times_ns, messages, JOINT_STATE)

    def add_axial_loads(self, stamps_ns: npt.ArrayLike, log_times_ns: np.ndarray | Sequence[int], forces: npt.ArrayLike,
                        frame_id: str = '') -> None:
        """``WrenchStamped`` messages with ``wrench.force.z`` = axial load in N."""
        connection = self._connection(AXIAL_LOAD_TOPIC, WRENCH_STAMPED)
        zero = self._vector(x=0.0, y=0.0, z=0.0)
        messages = (self._wrench_stamped(header=self._stamp(stamp, frame_id),
                                         wrench=self._wrench(force=self._vector(x=0.0, y=0.0, z=force),
                                                             torque=zero))
                    for stamp, force in zip(np.asarray(stamps_ns).tolist(),
                                            np.asarray(forces, dtype=float).tolist()))
        self._queue(connection, log_times_ns, messages, WRENCH_STAMPED)

    def add_temperatures(self, stamps_ns: npt.ArrayLike, log_times_ns: np.ndarray | Sequence[int],
                         temperatures: npt.ArrayLike, variance: float = 0.0, frame_id: str = '') -> None:
        """``Temperature`` messages in degC with the sensor's variance in K^2."""
        connection = self._connection(TEMPERATURE_TOPIC, TEMPERATURE)
        messages = (self._temperature(header=self._stamp(stamp, frame_id), temperature=value,
                                      variance=float(variance))
                    for stamp, value in zip(np.asarray(stamps_ns).tolist(),
                                            np.asarray(temperatures, dtype=float).tolist()))
        self._queue(connection, log_times_ns, messages, TEMPERATURE)

    # -- writing --------------------------------------------------------------------------------
    def flush(self, before_ns: int | None = None) -> None:
        """Write buffered messages logged before ``before_ns`` (all if None) in log-time order."""
        self._pending.sort(key=lambda item: (item[0], item[1]))
        if before_ns is None:
            ready, self._pending = self._pending, []
        else:
            cut = bisect.bisect_left(self._pending, before_ns, key=lambda item: item[0])
            ready, self._pending = self._pending[:cut], self._pending[cut:]
        assert self._writer is not None, 'the bag is closed'
        write = self._writer.write
        for log_time, _, connection, data in ready:
            write(connection, log_time, data)

    def close(self) -> None:
        """Write what is buffered and finish the bag (``metadata.yaml``, mcap index)."""
        if self._writer is None:
            return
        self.flush()
        self._writer.close()
        self._writer = None
        if self.storage == 'mcap-file':
            inner = self._bag_dir / f'{self._bag_dir.name}.mcap'
            inner.replace(self.path)
            shutil.rmtree(self._bag_dir)

    def abort(self) -> None:
        """Drop the unfinished bag."""
        if self._writer is not None:
            self._writer.abort()
            self._writer = None
        shutil.rmtree(self._bag_dir, ignore_errors=True)

    def __enter__(self) -> ContractBagWriter:
        """Context manager entry."""
        return self

    def __exit__(self, exc_type: type[BaseException] | None, exc: BaseException | None,
                 traceback: TracebackType | None) -> Literal[False]:
        """Finish the bag, or drop it when the body raised."""
        if exc_type is None:
            self.close()
        else:
            self.abort()
        return False
