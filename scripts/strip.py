#!/usr/bin/env python3
"""Side-by-side strips of renders, as README's docs/pipelines.png is made.

    python3 scripts/strip.py --crop X,Y,W,H [--halve] -o OUT.png A.png B.png ...

Each input (an 8-bit RGB or RGBA PNG, as `strandgraph render` writes) is
cropped to the rectangle, optionally halved by averaging 2x2 blocks, and the
results are placed left to right. Standard library only (zlib), so it runs
wherever the CLI does.
"""
import argparse
import struct
import sys
import zlib

SIGNATURE = b"\x89PNG\r\n\x1a\n"


def fail(path, message):
    sys.exit(f"{path}: {message}")


def read_png(path):
    """(width, height, channels, rows of bytes) of an 8-bit RGB(A) PNG."""
    data = open(path, "rb").read()
    if not data.startswith(SIGNATURE):
        fail(path, "not a PNG (bad signature at byte 0)")
    at, idat, header = 8, [], None
    while at + 8 <= len(data):
        length, kind = struct.unpack(">I4s", data[at : at + 8])
        body = data[at + 8 : at + 8 + length]
        if len(body) != length:
            fail(path, f"chunk {kind!r} at byte {at} runs past the end")
        if kind == b"IHDR":
            header = struct.unpack(">IIBBBBB", body)
        elif kind == b"IDAT":
            idat.append(body)
        at += 12 + length
    if header is None:
        fail(path, "no IHDR chunk")
    width, height, depth, colour, _, _, interlace = header
    channels = {2: 3, 6: 4}.get(colour)
    if depth != 8 or channels is None or interlace:
        fail(path, f"8-bit non-interlaced RGB or RGBA only (depth {depth}, colour type {colour})")
    raw = zlib.decompress(b"".join(idat))
    stride = width * channels
    if len(raw) != height * (stride + 1):
        fail(path, f"{len(raw)} bytes of pixel data, expected {height * (stride + 1)}")
    rows, previous = [], bytearray(stride)
    for y in range(height):
        line = raw[y * (stride + 1) : (y + 1) * (stride + 1)]
        rows.append(previous := unfilter(path, line[0], bytearray(line[1:]), previous, channels))
    return width, height, channels, rows


def unfilter(path, kind, row, above, bpp):
    """PNG filter types 0-4 undone in place (PNG spec §9.2)."""
    for i in range(len(row)):
        a = row[i - bpp] if i >= bpp else 0
        b = above[i]
        c = above[i - bpp] if i >= bpp else 0
        if kind == 1:
            row[i] = (row[i] + a) & 255
        elif kind == 2:
            row[i] = (row[i] + b) & 255
        elif kind == 3:
            row[i] = (row[i] + (a + b) // 2) & 255
        elif kind == 4:
            p = a + b - c
            pa, pb, pc = abs(p - a), abs(p - b), abs(p - c)
            row[i] = (row[i] + (a if pa <= pb and pa <= pc else b if pb <= pc else c)) & 255
        elif kind != 0:
            fail(path, f"unknown row filter {kind}")
    return row


def crop_rgb(path, image, x, y, w, h):
    width, height, channels, rows = image
    if x < 0 or y < 0 or x + w > width or y + h > height:
        fail(path, f"crop {x},{y},{w},{h} leaves the {width}x{height} image")
    out = []
    for row in rows[y : y + h]:
        px = row[x * channels : (x + w) * channels]
        out.append(bytearray(b for i, b in enumerate(px) if i % channels < 3))
    return out


def halve(rows):
    out = []
    for top, bottom in zip(rows[0::2], rows[1::2]):
        line = bytearray()
        for i in range(0, len(top) - 5, 6):
            for k in range(3):
                s = top[i + k] + top[i + 3 + k] + bottom[i + k] + bottom[i + 3 + k]
                line.append((s + 2) // 4)
        out.append(line)
    return out


def write_png(path, rows):
    width, height = len(rows[0]) // 3, len(rows)
    raw = b"".join(b"\x00" + bytes(r) for r in rows)

    def chunk(kind, body):
        return struct.pack(">I", len(body)) + kind + body + struct.pack(">I", zlib.crc32(kind + body))

    ihdr = struct.pack(">IIBBBBB", width, height, 8, 2, 0, 0, 0)
    with open(path, "wb") as f:
        f.write(SIGNATURE + chunk(b"IHDR", ihdr) + chunk(b"IDAT", zlib.compress(raw, 9)) + chunk(b"IEND", b""))


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--crop", required=True, help="X,Y,W,H in pixels of every input")
    ap.add_argument("--halve", action="store_true", help="average 2x2 blocks after cropping")
    ap.add_argument("-o", "--output", required=True)
    ap.add_argument("inputs", nargs="+")
    args = ap.parse_args()
    try:
        x, y, w, h = (int(v) for v in args.crop.split(","))
    except ValueError:
        sys.exit(f"--crop {args.crop}: expected four integers X,Y,W,H")
    panels = []
    for path in args.inputs:
        rows = crop_rgb(path, read_png(path), x, y, w, h)
        panels.append(halve(rows) if args.halve else rows)
    write_png(args.output, [b"".join(p[i] for p in panels) for i in range(len(panels[0]))])


if __name__ == "__main__":
    main()
