"""An 8-bit RGB or RGBA PNG read with the standard library (struct, zlib), every row filter
undone: the one reader of the tests that look at screenshots and png-seq frames
(tests/viewer/test_resize_framing.sh, test_timeline_lanes.sh, tests/e2e/test_turned_face.sh;
they put this folder on PYTHONPATH)."""
import struct
import zlib


def read_png(path):
    """(width, height, bpp, rows) of the PNG at path: bpp 3 (RGB) or 4 (RGBA), rows a list of
    height bytearrays of width * bpp bytes. Asserts an 8-bit RGB or RGBA file."""
    d = open(path, "rb").read()
    assert d[:8] == b"\x89PNG\r\n\x1a\n", path
    at, idat, w, h, bpp = 8, b"", 0, 0, 0
    while at < len(d):
        n, kind = struct.unpack(">I4s", d[at:at + 8])
        body = d[at + 8:at + 8 + n]
        if kind == b"IHDR":
            w, h, depth, ctype = struct.unpack(">IIBB", body[:10])
            assert depth == 8 and ctype in (2, 6), (path, depth, ctype)
            bpp = 3 if ctype == 2 else 4
        elif kind == b"IDAT":
            idat += body
        at += 12 + n
    raw, stride, rows, prev = zlib.decompress(idat), w * bpp, [], bytearray(w * bpp)
    for y in range(h):
        f, line = raw[y * (stride + 1)], bytearray(raw[y * (stride + 1) + 1:(y + 1) * (stride + 1)])
        for i in range(stride):
            a = line[i - bpp] if i >= bpp else 0
            b, c = prev[i], prev[i - bpp] if i >= bpp else 0
            if f == 1:
                line[i] = (line[i] + a) & 255
            elif f == 2:
                line[i] = (line[i] + b) & 255
            elif f == 3:
                line[i] = (line[i] + (a + b) // 2) & 255
            elif f == 4:
                p = a + b - c
                pa, pb, pc = abs(p - a), abs(p - b), abs(p - c)
                line[i] = (line[i] + (a if pa <= pb and pa <= pc else b if pb <= pc else c)) & 255
        rows.append(line)
        prev = line
    return w, h, bpp, rows
