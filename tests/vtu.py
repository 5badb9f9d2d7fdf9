"""vtu -- the test suites' own reader of pd's .vtu files (VTK XML
UnstructuredGrid, binary appended data), independent of the C writer and of
meshio: read(path) parses the XML header, then decodes every array, raw
(a UInt64 byte count, then the values) or compressed by zlib (the
attribute compressor="vtkZLibDataCompressor": a UInt64 header of the number
of blocks, the block size, the size of a partial last block or 0 and the
compressed size of each block, then the blocks, each compressed alone).
Every size is checked against the header: a short or long array fails.
"""
import struct
import xml.etree.ElementTree as ET
import zlib

import numpy as np

_TYPES = {"Float64": "<f8", "Float32": "<f4", "Int64": "<i8", "Int32": "<i4", "UInt8": "u1"}


class Grid:
    """points (n, 3), cells (connectivity, offsets, types), point_data by
    name (n, ncomp) or (n,), root (the XML element), compressed (bool),
    blocks (name -> the number of zlib blocks of the array)."""


def _decode(raw, at, a, expect):
    """The array of DataArray a at byte `at` of the appended block."""
    dtype = np.dtype(_TYPES[a.get("type")])
    if a.get("_compressed"):
        nblocks, size, last = struct.unpack_from("<3Q", raw, at)
        zsizes = struct.unpack_from("<%dQ" % nblocks, raw, at + 24)
        at += 24 + 8 * nblocks
        body = b""
        for k, z in enumerate(zsizes):
            piece = zlib.decompress(raw[at:at + z])
            full = size if (k + 1 < nblocks or last == 0) else last
            assert len(piece) == full, (a.get("Name"), k, len(piece), full)
            body += piece
            at += z
        blocks = nblocks
    else:
        (nbytes,) = struct.unpack_from("<Q", raw, at)
        body = raw[at + 8:at + 8 + nbytes]
        assert len(body) == nbytes
        blocks = 0
    assert expect is None or len(body) == expect * dtype.itemsize, (a.get("Name"), len(body), expect)
    return np.frombuffer(body, dtype), blocks


def read(path):
    raw = open(path, "rb").read()
    head = raw.index(b"<AppendedData")
    root = ET.fromstring(raw[:head].decode() + "</VTKFile>")
    assert root.get("type") == "UnstructuredGrid", root.get("type")
    assert root.get("byte_order") == "LittleEndian" and root.get("header_type") == "UInt64"
    assert raw.rstrip().endswith(b"</AppendedData>\n</VTKFile>"), "truncated"
    compressor = root.get("compressor")
    assert compressor in (None, "vtkZLibDataCompressor"), compressor
    app = raw.index(b"_", raw.index(b'<AppendedData encoding="raw">')) + 1
    piece = root.find("./UnstructuredGrid/Piece")
    n, ncells = int(piece.get("NumberOfPoints")), int(piece.get("NumberOfCells"))
    g = Grid()
    g.root, g.compressed, g.point_data, g.blocks = root, compressor is not None, {}, {}
    arrays = {}
    for part in ("PointData", "Points", "Cells"):
        for a in piece.find(part).iter("DataArray"):
            assert a.get("format") == "appended"
            a.set("_compressed", "1" if g.compressed else "")
            comp = int(a.get("NumberOfComponents", "1"))
            name = a.get("Name")
            # connectivity: checked against the last offset below
            count = n * comp if part != "Cells" else (None if name == "connectivity" else ncells)
            v, g.blocks[name] = _decode(raw, app + int(a.get("offset")), a, count)
            v = v.reshape(-1, comp) if comp > 1 else v
            arrays[name] = v
            if part == "PointData":
                g.point_data[name] = v
    assert len(arrays["connectivity"]) == (arrays["offsets"][-1] if ncells else 0)
    g.points = arrays["Points"]
    g.cells = (arrays["connectivity"], arrays["offsets"], arrays["types"])
    return g
