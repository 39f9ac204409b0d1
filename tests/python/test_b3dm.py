"""The .b3dm container: tables kept byte for byte, lengths and 8-byte alignment rebuilt."""
import json
import struct

import pytest


def glb(payload):
    """A minimal GLB: header and one JSON chunk (padded with spaces to 4 bytes)."""
    text = json.dumps({"asset": {"version": "2.0"}, "extras": payload}).encode()
    text += b" " * (-len(text) % 4)
    return struct.pack("<4sII", b"glTF", 2, 12 + 8 + len(text)) + struct.pack("<I4s", len(text), b"JSON") + text


def b3dm_bytes(ft_json, ft_bin, bt_json, bt_bin, model):
    """A b3dm as a writer following the specification makes it (each part padded to 8 bytes)."""
    parts, offset = [], 28
    for data, fill in ((ft_json, b" "), (ft_bin, b"\0"), (bt_json, b" "), (bt_bin, b"\0")):
        data += fill * (-(offset + len(data)) % 8) if data else b""
        parts.append(data)
        offset += len(data)
    model += b"\0" * (-(offset + len(model)) % 8)
    return struct.pack("<4s6I", b"b3dm", 1, offset + len(model), *map(len, parts)) + b"".join(parts) + model


@pytest.fixture
def b3dm(tightex):
    from tightex import b3dm
    return b3dm


def test_round_trip_is_byte_identical(b3dm):
    data = b3dm_bytes(b'{"BATCH_LENGTH":3,"RTC_CENTER":{"byteOffset":0}}', struct.pack("<3d", 1.5, -2, 1e6),
                      b'{"id":{"byteOffset":0,"componentType":"UNSIGNED_INT","type":"SCALAR"}}', struct.pack("<3I", 7, 8, 9),
                      glb("x" * 5))
    tile = b3dm.parse_b3dm(data)
    assert tile.feature_table_binary[:24] == struct.pack("<3d", 1.5, -2, 1e6) and tile.glb[:4] == b"glTF"
    assert b3dm.build_b3dm(tile) == data


def test_new_glb_gets_lengths_and_padding(b3dm):
    data = b3dm_bytes(b'{"BATCH_LENGTH":0}', b"", b"", b"", glb("a"))
    tile = b3dm.parse_b3dm(data)
    tables = data[28:28 + sum(struct.unpack_from("<4I", data, 12))]
    tile.glb = glb("a much longer model than before" * 3)
    out = b3dm.build_b3dm(tile)
    magic, version, length, ft_json, ft_bin, bt_json, bt_bin = struct.unpack_from("<4s6I", out)
    assert (magic, version, length) == (b"b3dm", 1, len(out)) and len(out) % 8 == 0
    start = 28 + ft_json + ft_bin + bt_json + bt_bin
    assert start % 8 == 0 and out[28:start] == tables
    assert out[start:start + len(tile.glb)] == tile.glb and set(out[start + len(tile.glb):]) <= {0}
    assert b3dm.parse_b3dm(out).glb == tile.glb


def test_bad_b3dm_is_input_error(tightex, b3dm):
    good = b3dm_bytes(b'{"BATCH_LENGTH":0}', b"", b"", b"", glb(1))
    for data, problem in ((good[:20], "shorter"), (b"i3dm" + good[4:], "magic"), (good[:40], "byteLength"),
                          (good[:28] + b"x" * (len(good) - 28), "GLB")):
        with pytest.raises(tightex.InputError, match=problem):
            b3dm.parse_b3dm(data, "tile.b3dm")
