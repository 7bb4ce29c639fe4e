"""Bad input: the tolerant MCAP reader shared by `replay` and `analyze`
(recording/mcap_io.py). ROS-free and fast: synthetic files written with the mcap
library (several chunks, every compression), then cut or damaged on purpose.

- an intact file reads exactly as the mcap library reads it (same messages, same order);
- a file cut at any byte never raises: the problem names the file and says "truncated", and
  every message before the cut that survived is returned unchanged (a prefix of the original);
- a damaged stretch in the middle is reported (CRC or corrupt data) and the messages after it
  are still read (resynchronisation on the next record);
- something that is not MCAP, or an empty file, is reported with its path;
- decoding (rclpy's serialization, no ROS graph): messages that do not decode are counted per
  topic, any other error of a decoder propagates; an unreadable rosbag2 metadata.yaml is said.
"""
import os
import struct

import pytest

from recording.mcap_io import McapFile, McapReadError

N_MESSAGES = 600


def _write(path, compression="zstd", chunk_size=4096, use_chunking=True, extra=0):
    from mcap.writer import CompressionType, Writer
    comp = {"zstd": CompressionType.ZSTD, "lz4": CompressionType.LZ4, "": CompressionType.NONE}[compression]
    with open(path, "wb") as f:
        w = Writer(f, chunk_size=chunk_size, compression=comp, use_chunking=use_chunking)
        w.start(profile="ros2", library="test")
        sid = w.register_schema(name="std_msgs/msg/String", encoding="ros2msg", data=b"string data\n")
        chans = [w.register_channel(topic=f"/t{i}", message_encoding="cdr", schema_id=sid,
                                    metadata={"offered_qos_profiles": ""}) for i in range(3)]
        for k in range(N_MESSAGES):
            payload = struct.pack("<I", k) + os.urandom(40 + k % 50 + extra)  # incompressible, varying size
            w.add_message(channel_id=chans[k % 3], log_time=k * 10_000_000, publish_time=k * 10_000_000,
                          data=payload, sequence=k)
        w.finish()
    return path


def _library_messages(path):
    from mcap.reader import make_reader
    with open(path, "rb") as f:
        return [(c.topic, m.log_time, m.sequence, m.data)
                for _, c, m in make_reader(f).iter_messages(log_time_order=False)]


def _ours(mf):
    return [(m.topic, m.log_time, m.sequence, m.data) for m in mf.messages()]


@pytest.mark.parametrize("compression,chunked", [("zstd", True), ("lz4", True), ("", True), ("", False)])
def test_intact_file_reads_like_the_mcap_library(tmp_path, compression, chunked):
    path = _write(str(tmp_path / "a.mcap"), compression, use_chunking=chunked)
    mf = McapFile(path)
    assert _ours(mf) == _library_messages(path)
    assert mf.complete and not mf.problems and mf.message_count == N_MESSAGES
    assert [m.log_time for m in mf.messages_in_time_order()] == sorted(k * 10_000_000 for k in range(N_MESSAGES))
    assert "OK" in mf.report()


@pytest.mark.parametrize("compression,chunked", [("zstd", True), ("lz4", True), ("", True), ("", False)])
def test_file_cut_anywhere_is_reported_and_its_readable_part_kept(tmp_path, compression, chunked):
    path = _write(str(tmp_path / "a.mcap"), compression, use_chunking=chunked)
    full = _library_messages(path)
    data = open(path, "rb").read()
    cut_path = str(tmp_path / "cut.mcap")
    recovered = []
    # the summary starts after the last message; cutting inside it loses no message
    for cut in list(range(0, 200, 7)) + list(range(200, len(data), max(1, len(data) // 97))):
        with open(cut_path, "wb") as f:
            f.write(data[:cut])
        mf = McapFile(cut_path)
        got = _ours(mf)  # never raises
        assert got == full[:len(got)], f"cut at {cut}: the readable part differs from the original"
        assert not mf.complete
        assert mf.problems, f"cut at {cut} of {len(data)} not reported"
        report = mf.report()
        assert cut_path in report
        assert ("truncated" in report or "empty file" in report or "not an MCAP file" in report), report
        recovered.append((cut, len(got)))
    # a cut in the middle keeps (nearly) everything before it: at most one chunk (4 KiB) is lost
    mid = [n for cut, n in recovered if abs(cut - len(data) // 2) < len(data) // 50]
    assert mid and min(mid) > N_MESSAGES * 0.4, recovered


def test_cut_inside_a_chunk_still_yields_its_complete_blocks(tmp_path):
    """One big zstd chunk (all messages): cut in its middle, the decompressor still gives the
    messages of the complete compressed blocks before the cut."""
    path = _write(str(tmp_path / "big.mcap"), "zstd", chunk_size=10 ** 7, extra=1000)  # 0.6 MB: 5 zstd blocks
    data = open(path, "rb").read()
    cut = str(tmp_path / "cut.mcap")
    with open(cut, "wb") as f:
        f.write(data[:int(len(data) * 0.7)])
    mf = McapFile(cut)
    got = _ours(mf)
    assert 0 < len(got) < N_MESSAGES and got == _library_messages(path)[:len(got)]
    assert "ends inside a chunk" in mf.report() and f"{len(got)} messages recovered" in mf.report()


@pytest.mark.parametrize("garbage", [b"\xff", b"\x00", b"random"])
def test_damaged_middle_is_reported_and_later_messages_read(tmp_path, garbage):
    path = _write(str(tmp_path / "a.mcap"), "zstd", chunk_size=4096)
    full = _library_messages(path)
    data = bytearray(open(path, "rb").read())
    start, n = len(data) // 3, 300
    data[start:start + n] = os.urandom(n) if garbage == b"random" else garbage * n
    bad = str(tmp_path / "bad.mcap")
    with open(bad, "wb") as f:
        f.write(data)
    mf = McapFile(bad)
    got = _ours(mf)
    assert mf.problems and not mf.complete
    report = mf.report()
    assert bad in report and ("CRC" in report or "corrupt" in report or "unreadable" in report), report
    good = [m for m in got if m in full]
    # at most the damaged chunk (or two) is lost; messages after the damage are back
    assert len(good) > N_MESSAGES * 0.8, report
    assert good[-1] == full[-1]
    assert [full.index(m) for m in good] == sorted(full.index(m) for m in good)  # original order


def test_not_an_mcap_file_and_empty_file(tmp_path):
    text = tmp_path / "notes.mcap"
    text.write_text("this is not a recording\n" * 20)
    mf = McapFile(str(text))
    assert _ours(mf) == [] and mf.problems
    assert str(text) in mf.report() and "not an MCAP file" in mf.report()
    empty = tmp_path / "empty.mcap"
    empty.write_bytes(b"")
    mf = McapFile(str(empty))
    assert _ours(mf) == [] and "empty file" in mf.report() and str(empty) in mf.report()
    with pytest.raises(McapReadError, match="missing.mcap"):
        McapFile(str(tmp_path / "missing.mcap"))


# -- decoding: corrupt messages are counted per topic, anything else propagates -----------------
# (these need rclpy's serialization, not a ROS graph)
def _write_strings(path, good, corrupt_on, n_corrupt):
    """/good and /bad: std_msgs/String; n_corrupt messages of topic corrupt_on end inside their
    string's length field."""
    from mcap.writer import Writer
    from rclpy.serialization import serialize_message
    from std_msgs.msg import String
    with open(path, "wb") as f:
        w = Writer(f)
        w.start(profile="ros2", library="test")
        sid = w.register_schema(name="std_msgs/msg/String", encoding="ros2msg", data=b"string data\n")
        chans = {t: w.register_channel(topic=t, message_encoding="cdr", schema_id=sid) for t in ("/good", "/bad")}
        k = 0
        for topic in ("/good", "/bad"):
            for i in range(good):
                w.add_message(channel_id=chans[topic], log_time=k, publish_time=k, sequence=k,
                              data=serialize_message(String(data=f"hello {i}")))
                k += 1
        for i in range(n_corrupt):
            data = serialize_message(String(data="corrupt"))[:6]
            w.add_message(channel_id=chans[corrupt_on], log_time=k, publish_time=k, sequence=k, data=data)
            k += 1
        w.finish()
    return path


def test_decoder_counts_corrupt_messages_per_topic(tmp_path):
    from recording.mcap_io import Decoder
    mf = McapFile(_write_strings(str(tmp_path / "s.mcap"), good=4, corrupt_on="/bad", n_corrupt=3))
    dec = Decoder()
    decoded = [dec.decode(m) for m in mf.messages()]
    assert [d.data for d in decoded if d is not None] == [f"hello {i}" for i in range(4)] * 2
    assert dec.errors == {"/bad": 3}
    assert dec.report() == ["/bad: 3 message(s) do not decode as its type (corrupt data); left out"]


def test_decoder_with_the_files_schema_counts_corrupt_messages_too(tmp_path, monkeypatch):
    from recording import mcap_io

    def not_installed(type_name):
        raise ImportError(f"type {type_name} is not importable here")
    monkeypatch.setattr(mcap_io, "message_class", not_installed)
    mf = McapFile(_write_strings(str(tmp_path / "s.mcap"), good=2, corrupt_on="/bad", n_corrupt=2))
    dec = mcap_io.Decoder()
    decoded = [dec.decode(m) for m in mf.messages()]
    assert [d.data for d in decoded if d is not None] == ["hello 0", "hello 1"] * 2
    assert dec.errors == {"/bad": 2}
    assert any("decoded with the file's own schema" in n for n in dec.notes)


def test_decoder_lets_an_error_that_is_not_corrupt_data_propagate(tmp_path, monkeypatch):
    """A bug (here: the deserializer raising TypeError) is not counted as a corrupt message."""
    import rclpy.serialization
    from recording.mcap_io import Decoder

    def broken(data, cls):
        raise TypeError("a programming error")
    monkeypatch.setattr(rclpy.serialization, "deserialize_message", broken)
    mf = McapFile(_write_strings(str(tmp_path / "s.mcap"), good=1, corrupt_on="/bad", n_corrupt=0))
    with pytest.raises(TypeError, match="a programming error"):
        Decoder().decode(next(mf.messages()))


def test_unreadable_bag_metadata_is_said_and_the_files_present_used(tmp_path):
    from recording.mcap_io import locate_recording
    bag = tmp_path / "bag"
    bag.mkdir()
    _write(str(bag / "bag_0.mcap"))
    (bag / "metadata.yaml").write_text("rosbag2_bagfile_information: [unclosed\n")
    path, note = locate_recording(str(bag))
    assert path == str(bag / "bag_0.mcap")
    assert "metadata.yaml is unreadable" in note and "went by the files present" in note


def test_false_record_in_damaged_data_does_not_swallow_later_chunks(tmp_path):
    """Damage after a chunk that happens to hold a plausible message header (0x05, a known
    channel, a length ending on a real record) must not make the reader jump over the chunks
    between: the resynchronisation takes the first real chunk."""
    path = _write(str(tmp_path / "a.mcap"), "lz4", chunk_size=4096)
    full = _library_messages(path)
    data = bytearray(open(path, "rb").read())
    chunks, pos = [], 8
    while data[pos] != 0x0F:  # data end
        length = struct.unpack_from("<Q", data, pos + 1)[0]
        if data[pos] == 0x06:
            chunks.append((pos, pos + 9 + length))
        pos += 9 + length
    assert len(chunks) >= 6
    first_end, last_start = chunks[1][1], chunks[-1][0]
    fake_at = first_end + 40
    data[first_end:fake_at] = b"\xa5" * 40
    fake_len = last_start - (fake_at + 9)  # ends exactly where the last chunk begins
    data[fake_at:fake_at + 11] = b"\x05" + struct.pack("<Q", fake_len) + struct.pack("<H", 1)
    bad = str(tmp_path / "bad.mcap")
    with open(bad, "wb") as f:
        f.write(data)
    mf = McapFile(bad)
    got = _ours(mf)
    assert mf.problems and "corrupt" in mf.report()
    assert got == full, f"{len(full) - len(got)} of {len(full)} messages lost: {mf.report()}"
