#!/usr/bin/env python3
"""Usage: scripts/check_vtu.py CASE/particles [...]

Validates kick's .vtu/.pvd files with the standard library only:
the XML header (everything up to the raw appended block, closed with the
file's own closing tags) must parse with xml.etree; each appended array is
decoded from its offset (vtkZLibDataCompressor layout with UInt64 headers:
[blocks, block size, last partial block size, compressed sizes...] then
zlib blocks, decompressed with Python's zlib) and
checked against NumberOfPoints/NumberOfComponents; every .pvd must parse,
list every .vtu of its folder once, with times equal to the files'
TimeValue and in ascending order. Prints a summary; exits 1 on any failure."""
import os, struct, sys, glob, zlib
import xml.etree.ElementTree as ET

TYPES = {"Float32": ("f", 4), "Float64": ("d", 8), "Int32": ("i", 4),
         "UInt32": ("I", 4), "Int64": ("q", 8), "UInt8": ("B", 1)}

def read_vtu(path):
    raw = open(path, "rb").read()
    tag = b'<AppendedData encoding="raw">'
    at = raw.index(tag)
    us = raw.index(b"_", at + len(tag))
    data = raw[us + 1:]
    assert data.endswith(b"\n</AppendedData>\n</VTKFile>\n"), "file ends with its closing tags"
    head = raw[:at].decode() + "</VTKFile>"
    root = ET.fromstring(head)            # the header is well-formed XML
    assert root.get("type") == "UnstructuredGrid" and root.get("header_type") == "UInt64"
    assert root.get("byte_order") == "LittleEndian"
    piece = root.find("UnstructuredGrid/Piece")
    n = int(piece.get("NumberOfPoints")); ncells = int(piece.get("NumberOfCells"))
    fd = {a.get("Name"): a.text.strip() for a in root.findall("UnstructuredGrid/FieldData/DataArray")}
    arrays, ends = {}, []
    for a in root.iter("DataArray"):
        if a.get("format") != "appended":
            continue
        off = int(a.get("offset")); fmt, w = TYPES[a.get("type")]
        assert root.get("compressor") == "vtkZLibDataCompressor"
        (nblocks, bsize, last) = struct.unpack_from("<3Q", data, off)
        sizes = struct.unpack_from("<%dQ" % nblocks, data, off + 24)
        at = off + 24 + 8 * nblocks
        raw_bytes = b""
        for k, size in enumerate(sizes):
            block = zlib.decompress(data[at:at + size])
            full = k < nblocks - 1 or last == 0
            assert len(block) == (bsize if full else last), (path, k, len(block))
            raw_bytes += block; at += size
        comps = int(a.get("NumberOfComponents", "1"))
        vals = struct.unpack("<%d%s" % (len(raw_bytes) // w, fmt), raw_bytes)
        arrays[a.get("Name")] = (comps, vals)
        ends.append(at)
    # The blocks tile the appended data exactly (nothing overlaps or is left over).
    assert max(ends) == len(data) - len(b"\n</AppendedData>\n</VTKFile>\n"), path
    for name in ["Points", "pressure", "accel", "J", "id", "velocity"]:
        comps, vals = arrays[name]
        assert len(vals) == comps * n, (path, name, len(vals), n)
    conn = arrays["connectivity"][1]; offs = arrays["offsets"][1]; types = arrays["types"][1]
    # One VTK_VERTEX cell per particle.
    assert ncells == n and list(conn) == list(range(n)) and list(offs) == list(range(1, n + 1))
    assert set(types) <= {1} and len(types) == n
    z = arrays["Points"][1][2::3]
    assert all(v == 0.0 for v in z)
    return float(fd["TimeValue"]), int(fd["Step"]), n, arrays

def check_folder(folder):
    vtus = sorted(glob.glob(os.path.join(folder, "*.vtu")))
    if not vtus:
        return 0
    times = {}
    for v in vtus:
        t, step, n, _ = read_vtu(v)
        assert os.path.basename(v).endswith("_%09d.vtu" % step), v
        times[os.path.basename(v)] = t
    pvd = os.path.join(folder, os.path.basename(folder.rstrip("/")) + ".pvd")
    root = ET.parse(pvd).getroot()
    assert root.get("type") == "Collection"
    rows = [(float(d.get("timestep")), d.get("file")) for d in root.iter("DataSet")]
    assert sorted(f for _, f in rows) == sorted(times), "pvd lists every .vtu once"
    assert all(times[f] == t for t, f in rows), "pvd times are the files' TimeValue"
    assert [t for t, _ in rows] == sorted(t for t, _ in rows), "ascending"
    return len(vtus)

if __name__ == "__main__":
    total = 0
    for top in sys.argv[1:]:
        for folder in [top] + sorted(p for p in glob.glob(os.path.join(top, "*")) if os.path.isdir(p)):
            k = check_folder(folder)
            print("%s: %d .vtu files and the .pvd valid" % (folder, k))
            total += k
    print("OK: %d files" % total)
