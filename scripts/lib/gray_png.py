#!/usr/bin/env python3
"""Grayscale PNGs (8- or 16-bit, not interlaced) mirrored or shifted, with the standard library.

    gray_png.py mirror IN.png OUT.png
    gray_png.py shift DX DY IN.png OUT.png
    gray_png.py upside-down IN.png OUT.png

A depth frame mirrored left to right, with the principal point at cx' = (width - 1) - cx, shows a
left hand where the frame showed a right one (docs/TRACKER.md, "Left hands"). Shifted by whole
pixels (pixel (u, v) moves to (u + DX, v + DY), the uncovered border reads 0: no depth), with the
principal point at (cx + DX, cy + DY), it shows the same scene on a pixel grid moved under it.
Turned upside down (mirrored left to right and top to bottom: a half turn about the optical axis),
with the principal point at ((width - 1) - cx, (height - 1) - cy), it shows the same hand, still a
right one, through a camera mounted upside down. What scripts/eval-real-still makes of the SR305's
right hands.
"""
import struct
import sys
import zlib


def read_gray(path):
    """Width, height, bytes per pixel and the unfiltered rows of a grayscale PNG."""
    data = open(path, "rb").read()
    if data[:8] != b"\x89PNG\r\n\x1a\n":
        sys.exit(f"gray_png: {path}: not a PNG")
    pos, idat, header = 8, b"", None
    while pos < len(data):
        (length,) = struct.unpack(">I", data[pos:pos + 4])
        kind, body = data[pos + 4:pos + 8], data[pos + 8:pos + 8 + length]
        if kind == b"IHDR":
            header = struct.unpack(">IIBBBBB", body)
        elif kind == b"IDAT":
            idat += body
        pos += 12 + length
    width, height, depth, colour, _, _, interlace = header
    if colour != 0 or depth not in (8, 16) or interlace != 0:
        sys.exit(f"gray_png: {path}: not an 8- or 16-bit grayscale, non-interlaced PNG")
    bpp = depth // 8
    stride = width * bpp
    raw = zlib.decompress(idat)
    rows, previous = [], bytearray(stride)
    for y in range(height):
        kind = raw[y * (stride + 1)]
        row = bytearray(raw[y * (stride + 1) + 1:(y + 1) * (stride + 1)])
        for x in range(stride):
            left = row[x - bpp] if x >= bpp else 0
            up = previous[x]
            up_left = previous[x - bpp] if x >= bpp else 0
            if kind == 1:
                row[x] = (row[x] + left) & 0xFF
            elif kind == 2:
                row[x] = (row[x] + up) & 0xFF
            elif kind == 3:
                row[x] = (row[x] + (left + up) // 2) & 0xFF
            elif kind == 4:  # Paeth
                p = left + up - up_left
                pa, pb, pc = abs(p - left), abs(p - up), abs(p - up_left)
                row[x] = (row[x] + (left if pa <= pb and pa <= pc else up if pb <= pc else up_left)) & 0xFF
        rows.append(bytes(row))
        previous = row
    return width, height, depth, rows


def write_gray(path, width, height, depth, rows):
    def chunk(kind, body):
        return struct.pack(">I", len(body)) + kind + body + struct.pack(">I", zlib.crc32(kind + body) & 0xFFFFFFFF)

    raw = b"".join(b"\x00" + row for row in rows)
    with open(path, "wb") as out:
        out.write(b"\x89PNG\r\n\x1a\n")
        out.write(chunk(b"IHDR", struct.pack(">IIBBBBB", width, height, depth, 0, 0, 0, 0)))
        out.write(chunk(b"IDAT", zlib.compress(raw, 6)))
        out.write(chunk(b"IEND", b""))


def mirrored(width, bpp, rows):
    return [b"".join(row[x * bpp:(x + 1) * bpp] for x in reversed(range(width))) for row in rows]


def upside_down(width, bpp, rows):
    return list(reversed(mirrored(width, bpp, rows)))


def shifted(width, height, bpp, rows, dx, dy):
    blank = bytes(width * bpp)
    out = []
    for v in range(height):
        row = rows[v - dy] if 0 <= v - dy < height else blank
        if dx >= 0:
            row = bytes(min(dx, width) * bpp) + row[:max(0, width - dx) * bpp]
        else:
            row = row[min(-dx, width) * bpp:] + bytes(min(-dx, width) * bpp)
        out.append(row)
    return out


def main():
    args = sys.argv[1:]
    if len(args) == 3 and args[0] == "mirror":
        width, height, depth, rows = read_gray(args[1])
        write_gray(args[2], width, height, depth, mirrored(width, depth // 8, rows))
    elif len(args) == 3 and args[0] == "upside-down":
        width, height, depth, rows = read_gray(args[1])
        write_gray(args[2], width, height, depth, upside_down(width, depth // 8, rows))
    elif len(args) == 5 and args[0] == "shift":
        try:
            dx, dy = int(args[1]), int(args[2])
        except ValueError:
            sys.exit(f"gray_png: shift: DX and DY must be whole pixels, got {args[1]!r} {args[2]!r}")
        width, height, depth, rows = read_gray(args[3])
        write_gray(args[4], width, height, depth, shifted(width, height, depth // 8, rows, dx, dy))
    else:
        sys.exit("usage: gray_png.py mirror IN.png OUT.png | gray_png.py shift DX DY IN.png OUT.png | "
                 "gray_png.py upside-down IN.png OUT.png")


if __name__ == "__main__":
    main()
