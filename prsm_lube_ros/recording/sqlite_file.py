# Copyright 2026 prsm_lube_ros developers
# SPDX-License-Identifier: Apache-2.0
"""rosbag2's sqlite3 storage (``.db3``), read with Python's own :mod:`sqlite3`.

A ``.db3`` file has a ``topics`` table (``id, name, type,
serialization_format, ...``), a ``messages`` table (``topic_id, timestamp,
data``, indexed by timestamp) and, from Iron on, ``message_definitions``
(``topic_type, encoding, encoded_message_definition``).  Messages are matched
to topics by ``topic_id`` alone, as rosbag2 does: the QoS profiles of
``metadata.yaml`` and of the database may differ (rosbag2's own ``talker``
test bag) without losing anything.  Files are opened read-only, and leave
no ``-wal``/``-shm`` files behind; anything sqlite3 complains about ends as
one :class:`SqliteProblem` line.  No ROS import.
"""
from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
import sqlite3
from collections.abc import Callable, Iterator

from ..errors import exception_text
from .mcap_file import McapProblem, zstd_frame

__all__ = ['FETCH_ROWS', 'SqliteFile', 'SqliteProblem', 'SqliteTopic']

#: rows fetched from sqlite3 at a time while streaming
FETCH_ROWS = 4096


class SqliteProblem(Exception):
    """The file is not a usable rosbag2 sqlite3 database; one line, without the file name."""


@dataclass
class SqliteTopic:
    """One row of the ``topics`` table with what the ``messages`` table holds for it."""

    id: int
    name: str
    msgtype: str
    serialization_format: str
    message_count: int = 0
    start_time: int | None = None   # ns
    end_time: int | None = None     # ns


def _connect(path: Path) -> sqlite3.Connection:
    """A read-only connection that leaves the bag's folder as it was.

    A database in WAL mode (as rosbag2 writes them) opened read-only makes
    sqlite3 create ``-wal`` and ``-shm`` files beside it; opened ``immutable``
    it does not.  Only when a non-empty ``-wal`` file holds data not yet in the
    database (a recorder that did not close it) is it opened to read that too.
    """
    path = Path(path).resolve()
    wal = path.with_name(path.name + '-wal')
    pending = wal.is_file() and wal.stat().st_size > 0
    try:
        return sqlite3.connect(f'{path.as_uri()}?{"mode=ro" if pending else "immutable=1"}', uri=True)
    except sqlite3.Error as err:
        raise SqliteProblem(f'not a readable sqlite3 database ({err})') from None


class SqliteFile:
    """One ``.db3`` file of a rosbag2 bag, listed at opening; problems raise :class:`SqliteProblem`."""

    def __init__(self, path: str | Path, compressed_messages: bool = False) -> None:
        self.path = Path(path)
        #: every message blob is a zstd frame (rosbag2's ``compression_mode: message``)
        self.compressed_messages = compressed_messages
        self.topics: dict[int, SqliteTopic] = {}
        self.definitions: dict[str, tuple[str, str]] = {}   # type -> (encoding, text)
        connection = _connect(self.path)
        try:
            for topic_id, name, msgtype, serialization in connection.execute(
                    'SELECT id, name, type, serialization_format FROM topics'):
                self.topics[int(topic_id)] = SqliteTopic(int(topic_id), str(name), str(msgtype), str(serialization))
            for topic_id, count, low, high in connection.execute(
                    'SELECT topic_id, COUNT(*), MIN(timestamp), MAX(timestamp) FROM messages GROUP BY topic_id'):
                topic = self.topics.get(int(topic_id))
                if topic is not None:
                    topic.message_count, topic.start_time, topic.end_time = int(count), int(low), int(high)
            tables = {row[0] for row in connection.execute("SELECT name FROM sqlite_master WHERE type='table'")}
            if 'message_definitions' in tables:
                for msgtype, encoding, text in connection.execute(
                        'SELECT topic_type, encoding, encoded_message_definition FROM message_definitions'):
                    self.definitions[str(msgtype)] = (str(encoding), str(text or ''))
        except (sqlite3.Error, TypeError, ValueError) as err:
            raise SqliteProblem(f'not a rosbag2 sqlite3 database ({exception_text(err)})') from None
        finally:
            connection.close()

    def messages(self, topic_ids: list[int], on_problem: Callable[[str], None]) -> Iterator[tuple[int, int, bytes]]:
        """``(topic_id, timestamp, data)`` of the given topics in timestamp order.

        A database that fails part way ends the stream with one line to ``on_problem``.
        """
        if not topic_ids:
            return
        connection = _connect(self.path)
        malformed = 0
        try:
            marks = ','.join('?' * len(topic_ids))
            cursor = connection.execute(
                f'SELECT topic_id, timestamp, data FROM messages WHERE topic_id IN ({marks}) '
                'ORDER BY timestamp, id', [int(i) for i in topic_ids])
            while True:
                rows = cursor.fetchmany(FETCH_ROWS)
                if not rows:
                    break
                for topic_id, timestamp, data in rows:
                    if not (isinstance(data, bytes) and isinstance(timestamp, int)):
                        malformed += 1
                        continue
                    if self.compressed_messages:
                        try:
                            data = zstd_frame(data)
                        except McapProblem:
                            malformed += 1
                            continue
                    yield topic_id, timestamp, data
        except sqlite3.Error as err:
            on_problem(f'reading stopped early: {exception_text(err)}')
        finally:
            connection.close()
        if malformed:
            on_problem(f'{malformed} row(s) of the messages table without a (zstd) blob and an integer timestamp '
                       'skipped')
