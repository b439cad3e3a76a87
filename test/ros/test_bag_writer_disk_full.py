# Copyright 2026 The formation_ros authors.
# SPDX-License-Identifier: Apache-2.0

"""
The bag writer on a disk that fills: its files are opened through a stand-in that refuses writes.

Each case writes numbered /clock messages, one flush per second of simulated time, and keeps
the stamps of the messages whose flush returned: what a reader finds must be exactly a prefix of
those, ending at a flush, and its count the one the writer reports.
"""

import errno
import io
import os

from formation_ros.ros.bag_writer import (BagWriteError, BagWriter, McapStorage, PARAMS_FILE,
                                          qos_of)
from formation_ros.ros.cdr import encode_clock
from formation_ros.tools.bag import read_messages, recover_bag
import pytest

CLOCK = '/clock'
PER_FLUSH = 50
NS = 10 ** 9


class Disk:
    """
    A filesystem with ``capacity`` bytes for the MCAP files, or one that fails from a write on.

    fail_at: the number of the write (1-based) that fails, writing half its bytes first; with
    ``once`` only that one, else every write after it too (no room is ever made). Without
    fail_at, writes beyond the capacity take what fits and then fail, and cutting a file gives
    its bytes back, as on a real disk.
    """

    def __init__(self, capacity=None, fail_at=None, once=False):
        """Describe the disk."""
        self.capacity, self.fail_at, self.once = capacity, fail_at, once
        self.writes = 0
        self.files = []

    def used(self):
        return sum(os.path.getsize(path) for path in self.files if os.path.exists(path))

    def storage(self):
        """Return a McapStorage class whose files are on this disk."""
        disk = self

        class OnThisDisk(McapStorage):
            OPENER = staticmethod(lambda path: disk.create(path))

        return OnThisDisk

    def create(self, path):
        self.files.append(path)
        return DiskFile(self, path)


class DiskFile(io.FileIO):
    """An unbuffered file of a :class:`Disk`."""

    def __init__(self, disk, path):
        """Create ``path`` on ``disk``."""
        super().__init__(path, 'xb')
        self.disk = disk

    def write(self, data):
        disk = self.disk
        disk.writes += 1
        view = memoryview(data).cast('B')
        if disk.fail_at is not None and (disk.writes == disk.fail_at or
                                         (disk.writes > disk.fail_at and not disk.once)):
            super().write(view[:len(view) // 2])
            raise OSError(errno.ENOSPC, os.strerror(errno.ENOSPC))
        if disk.capacity is not None:
            room = disk.capacity - disk.used()
            if room <= 0:
                raise OSError(errno.ENOSPC, os.strerror(errno.ENOSPC))
            view = view[:room]
        return super().write(view)


def record(path, disk, seconds=200, flushes_per_file=0):
    """
    Write ``seconds`` flushes of /clock messages until the writer fails.

    Return (writer, error, stamps of the messages whose flush returned, in order).
    """
    bag = BagWriter(str(path), flushes_per_file=flushes_per_file, storage=disk.storage())
    bag.add_topic(CLOCK, 'rosgraph_msgs/msg/Clock',
                  qos_of(reliable=False, transient_local=False, depth=1))
    bag.write_params({'num_robots': 4}, 0)
    flushed = []
    for second in range(seconds):
        batch = [second * NS + k * NS // PER_FLUSH for k in range(PER_FLUSH)]
        try:
            for stamp in batch:
                bag.write(CLOCK, stamp + 1, encode_clock(stamp))
            bag.flush()
        except BagWriteError as exc:
            return bag, exc, flushed
        flushed.extend(batch)
    bag.close()
    return bag, None, flushed


def stamps_in(path):
    topics, counts = read_messages(str(path))
    stamps = [message.clock.sec * NS + message.clock.nanosec for _, message in topics[CLOCK]]
    return stamps, counts


def assert_a_flushed_prefix(stamps, flushed):
    assert stamps == flushed[:len(stamps)]
    assert len(stamps) % PER_FLUSH == 0, 'the bag ends at a flush'


@pytest.mark.parametrize('fail_at', [7, 12, 25])
def test_a_write_that_fails_once_leaves_the_bag_whole_up_to_its_last_chunk(tmp_path, fail_at):
    bag, error, flushed = record(tmp_path / 'bag', Disk(fail_at=fail_at, once=True))
    assert error is not None and error.failure is not None
    failure = error.failure
    assert failure.reason == 'No space left on device' and failure.metadata
    stamps, counts = stamps_in(tmp_path / 'bag')
    assert stamps == flushed, 'every flush that returned is in the bag, and nothing else'
    assert failure.messages == sum(counts.values()) == len(stamps) + 1
    assert counts['/formation/params'] == 1
    assert failure.clock_ns == flushed[-1]
    assert failure.lost == PER_FLUSH
    assert failure.size == os.path.getsize(tmp_path / 'bag' / 'bag.mcap')
    with pytest.raises(BagWriteError):
        bag.write(CLOCK, 1, encode_clock(0))
    bag.close()


def test_a_full_disk_keeps_every_chunk_that_fits_with_the_metadata(tmp_path):
    disk = Disk(capacity=120_000)
    bag, error, flushed = record(tmp_path / 'bag', disk)
    assert error is not None and error.failure.metadata
    stamps, counts = stamps_in(tmp_path / 'bag')
    assert_a_flushed_prefix(stamps, flushed)
    assert len(stamps) >= len(flushed) - 2 * PER_FLUSH, 'at most a chunk given up for room'
    assert error.failure.messages == sum(counts.values()) == len(stamps) + 1
    assert error.failure.clock_ns == stamps[-1]
    assert error.failure.lost == len(flushed) + PER_FLUSH - len(stamps)
    assert disk.used() <= disk.capacity


def test_a_split_bag_on_a_full_disk_lists_every_file_it_keeps(tmp_path):
    disk = Disk(capacity=150_000)
    bag, error, flushed = record(tmp_path / 'bag', disk, flushes_per_file=3)
    assert error is not None and error.failure.metadata
    stamps, counts = stamps_in(tmp_path / 'bag')
    assert_a_flushed_prefix(stamps, flushed)
    assert error.failure.messages == sum(counts.values()) == len(stamps) + 1
    assert len([name for name in os.listdir(tmp_path / 'bag') if name.endswith('.mcap')]) > 3


def test_a_disk_that_never_makes_room_leaves_the_bag_for_recovery(tmp_path):
    bag, error, flushed = record(tmp_path / 'bag', Disk(fail_at=80))
    failure = error.failure
    assert not failure.metadata and 'formation_report recovers it' in failure.describe()
    assert not (tmp_path / 'bag' / 'metadata.yaml').exists()
    recovery = recover_bag(str(tmp_path / 'bag'))
    assert recovery.count == failure.messages
    stamps = sorted(stamp for stamp, _ in recovery.topics[CLOCK].messages)
    assert [stamp - 1 for stamp in stamps] == flushed[:len(stamps)]
    assert len(stamps) >= len(flushed) // 2, 'only the newest chunks are given up for room'


def test_a_bag_that_cannot_be_created_says_so(tmp_path):
    with pytest.raises(BagWriteError, match='cannot create .*No space left on device'):
        BagWriter(str(tmp_path / 'bag'), storage=Disk(fail_at=1).storage())
    assert not (tmp_path / 'bag').exists()


def test_a_params_file_that_does_not_fit_fails_the_same_way(tmp_path):
    bag = BagWriter(str(tmp_path / 'bag'), storage=Disk().storage())
    (tmp_path / 'bag' / PARAMS_FILE).mkdir()
    with pytest.raises(BagWriteError) as caught:
        bag.write_params({'num_robots': 4}, 0)
    assert caught.value.failure.messages == 0 and caught.value.failure.metadata
    topics, counts = read_messages(str(tmp_path / 'bag'))
    assert counts == {'/formation/params': 0} and topics == {}
