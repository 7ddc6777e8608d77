"""The MCAP tail repair of `rmcli bag reindex` (pure byte work, table-tested)."""

import struct

import pytest
from rm_bringup.cli.bag_reindex import MCAP_MAGIC, mcap_end_is_whole, repair_mcap_tail
from rm_bringup.cli.errors import BagError


def record(opcode, content):
    return struct.pack('<BQ', opcode, len(content)) + content


HEADER = record(0x01, b'\x04\x00\x00\x00ros2\x00\x00\x00\x00')
CHUNK = record(0x06, bytes(range(40)))
DATA_END = record(0x0F, b'\x00\x00\x00\x00')
FOOTER = record(0x02, bytes(20))
WHOLE = MCAP_MAGIC + HEADER + CHUNK + DATA_END + FOOTER + MCAP_MAGIC
ENDED = WHOLE  # what a repaired file is: the records kept, then the end a writer writes


@pytest.mark.parametrize(('content', 'cut'), [
    (MCAP_MAGIC + HEADER + CHUNK, 0),  # killed between two chunks
    (MCAP_MAGIC + HEADER + CHUNK + CHUNK[:17], 17),  # killed in a chunk
    (MCAP_MAGIC + HEADER + CHUNK + bytes(4096), 4096),  # zeros the file system left
    (MCAP_MAGIC + HEADER + CHUNK + DATA_END + FOOTER[:5], 5),  # killed in the summary
], ids=['between', 'mid-record', 'zeros', 'after-data-end'])
def test_a_killed_file_is_cut_after_its_last_whole_record_and_ended(tmp_path, content, cut):
    path = tmp_path / 'bag.mcap'
    path.write_bytes(content)
    assert repair_mcap_tail(path) == cut
    assert path.read_bytes() == ENDED
    assert mcap_end_is_whole(path.read_bytes())


def test_a_whole_file_is_left_alone(tmp_path):
    path = tmp_path / 'bag.mcap'
    path.write_bytes(WHOLE)
    assert repair_mcap_tail(path) is None
    assert path.read_bytes() == WHOLE


@pytest.mark.parametrize(('content', 'match'), [
    (b'', 'killed before its first chunk'),
    (b'PK\x03\x04' + bytes(60), 'not an MCAP file'),
    (MCAP_MAGIC + HEADER[:6], 'not even the MCAP header is whole'),
], ids=['empty', 'not-mcap', 'header-cut'])
def test_what_cannot_be_repaired_is_one_error_naming_the_file(tmp_path, content, match):
    path = tmp_path / 'bag.mcap'
    path.write_bytes(content)
    with pytest.raises(BagError, match=match) as err:
        repair_mcap_tail(path)
    assert str(path) in str(err.value)


@pytest.mark.parametrize('storage', ['mcap', 'sqlite3'])
def test_a_bag_without_its_metadata_reads_back_whole_after_reindex(write_bag, make, storage):
    from rm_bringup.cli.bag_info import describe
    from rm_bringup.cli.bag_io import open_bag, read_messages
    from rm_bringup.cli.bag_reindex import reindex

    twist = 'geometry_msgs/msg/Twist'
    samples = [('/vel_cmd', twist, 10**9 + i * 10**7, make(twist)) for i in range(30)]
    samples += [('/other', twist, 10**9 + i * 10**7 + 1, make(twist)) for i in range(5)]
    bag = write_bag(samples, storage=storage)
    (bag / 'metadata.yaml').unlink()  # as a killed recorder leaves it
    said = reindex(bag)
    assert said[-1].endswith('35 messages on 2 topics')
    with open_bag(bag) as reader:
        assert reader.message_count == 35
        assert len(list(read_messages(reader, bag, reader.connections))) == 35
    lines = describe(bag)
    assert any('Count: 30' in line for line in lines), lines
