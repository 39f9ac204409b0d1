"""3D Tiles 1.0 Batched 3D Model (.b3dm) content: a 28-byte header, a feature table and a batch table
(each JSON and binary), then a binary glTF (GLB).

``parse_b3dm`` splits a file into its parts, ``build_b3dm`` puts them back together: the tables are
kept byte for byte, the lengths in the header are recomputed, and every part starts and the whole
ends on an 8-byte boundary as the specification requires (a table that is not padded in the input
gets spaces (JSON) or zeros (binary); a conforming input's tables come back unchanged).
"""

import struct
from dataclasses import dataclass

from ._tightex import InputError

MAGIC = b"b3dm"
HEADER = struct.Struct("<4s6I")  # magic, version, byteLength, featureTableJSONByteLength,
# featureTableBinaryByteLength, batchTableJSONByteLength, batchTableBinaryByteLength


@dataclass
class B3dm:
    """The parts of a .b3dm file, each as the file holds it."""
    feature_table_json: bytes
    feature_table_binary: bytes
    batch_table_json: bytes
    batch_table_binary: bytes
    glb: bytes
    version: int = 1


def parse_b3dm(data, name="b3dm"):
    """Splits ``data`` (the bytes of a .b3dm file named ``name`` in messages) into its parts.

    Raises InputError naming the file and the problem for a wrong magic or version, a legacy header
    (batchLength / batchTableByteLength in place of the JSON lengths), or lengths beyond the file."""
    if len(data) < HEADER.size:
        raise InputError(f"{name}: {len(data)} bytes, shorter than the 28-byte b3dm header")
    magic, version, length, ft_json, ft_bin, bt_json, bt_bin = HEADER.unpack_from(data)
    if magic != MAGIC:
        raise InputError(f"{name}: magic {magic!r}, not b'b3dm'")
    if version != 1:
        raise InputError(f"{name}: b3dm version {version}, only version 1 is supported")
    if length > len(data):
        raise InputError(f"{name}: header byteLength {length} is more than the file's {len(data)} bytes")
    # A legacy header has a GLB's 'glTF' magic where the 28-byte header's fields or tables would be.
    if data[20:24] == b"glTF" or data[24:28] == b"glTF":
        raise InputError(f"{name}: legacy b3dm header (batchLength), not supported")
    offsets = [HEADER.size]
    for part in (ft_json, ft_bin, bt_json, bt_bin):
        offsets.append(offsets[-1] + part)
    if offsets[-1] > length:
        raise InputError(f"{name}: table lengths {ft_json} + {ft_bin} + {bt_json} + {bt_bin} run past byteLength {length}")
    parts = [data[offsets[i]:offsets[i + 1]] for i in range(4)]
    glb = data[offsets[-1]:length]
    if glb[:4] != b"glTF":
        raise InputError(f"{name}: the embedded model at byte {offsets[-1]} is not a GLB (magic {glb[:4]!r})")
    glb_length = struct.unpack_from("<I", glb, 8)[0] if len(glb) >= 12 else 0
    if glb_length < 12 or glb_length > len(glb):
        raise InputError(f"{name}: the embedded GLB's length {glb_length} does not fit the {len(glb)} bytes after the tables")
    return B3dm(*parts, glb=glb[:glb_length], version=version)


def _padded(data, start, fill):
    """``data`` followed by ``fill`` bytes so that start + length is a multiple of 8."""
    return data + fill * (-(start + len(data)) % 8)


def build_b3dm(tile):
    """The bytes of a .b3dm file holding ``tile``'s parts (a B3dm): the header's lengths from them,
    each part padded to end on an 8-byte boundary (see the module's doc), the GLB last, zeros after
    it to a multiple of 8."""
    parts = []
    offset = HEADER.size
    for data, fill in ((tile.feature_table_json, b" "), (tile.feature_table_binary, b"\0"), (tile.batch_table_json, b" "),
                       (tile.batch_table_binary, b"\0")):
        padded = _padded(data, offset, fill) if data else data
        parts.append(padded)
        offset += len(padded)
    glb = _padded(tile.glb, offset, b"\0")
    length = offset + len(glb)
    header = HEADER.pack(MAGIC, tile.version, length, *(len(p) for p in parts))
    return header + b"".join(parts) + glb
