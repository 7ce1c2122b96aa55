#!/usr/bin/env python3
"""The quick-look PNG of the fem bunny scene shows the bunny (a ctest; stdlib only).

check_png.py SIMIT SCENE NODE OUTDIR FRAMES

Runs SCENE (which has [output] png = "bunny.png") for FRAMES frames into OUTDIR, decodes the
PNG with zlib and struct, and checks: 480 x 360; a white-ish background in the corners; the
fraction of non-background pixels in a band around the measured one; the non-background
bounding box centred, filling the picture along one side, with the aspect ratio of the
bunny's last-frame positions projected by the view of README.md (u = (x - z) / sqrt 2,
v = (-x + 2 y - z) / sqrt 6); and the silhouette itself: the boundary faces of the tets in
NODE's .ele, projected and scan-converted here, cover the same pixels as the picture's ink
(intersection over union).
"""
import math
import os
import struct
import subprocess
import sys
import zlib

WIDTH, HEIGHT = 480, 360
INK_FRACTION = (0.30, 0.60)  # measured 0.461 after 2 frames
MIN_IOU = 0.97               # measured 0.9925


def fail(msg):
    print("FAIL: " + msg)
    sys.exit(1)


def paeth(a, b, c):
    p = a + b - c
    pa, pb, pc = abs(p - a), abs(p - b), abs(p - c)
    if pa <= pb and pa <= pc:
        return a
    return b if pb <= pc else c


def decode_png(path):
    """8-bit RGB, non-interlaced PNG -> (width, height, rows of bytes)."""
    data = open(path, "rb").read()
    if data[:8] != b"\x89PNG\r\n\x1a\n":
        fail(path + ": not a PNG signature")
    pos, idat, header = 8, b"", None
    while pos < len(data):
        (length,) = struct.unpack_from(">I", data, pos)
        kind = data[pos + 4:pos + 8]
        body = data[pos + 8:pos + 8 + length]
        (crc,) = struct.unpack_from(">I", data, pos + 8 + length)
        if zlib.crc32(kind + body) != crc:
            fail("%s: bad CRC in chunk %r" % (path, kind))
        if kind == b"IHDR":
            header = struct.unpack(">IIBBBBB", body)
        elif kind == b"IDAT":
            idat += body
        elif kind == b"IEND":
            break
        pos += 12 + length
    width, height, depth, color, _, _, interlace = header
    if (depth, color, interlace) != (8, 2, 0):
        fail("%s: expected 8-bit RGB, not interlaced; got depth %d color %d interlace %d"
             % (path, depth, color, interlace))
    raw = zlib.decompress(idat)
    stride, bpp = 3 * width, 3
    rows, prev = [], bytearray(stride)
    for y in range(height):
        f = raw[y * (stride + 1)]
        line = bytearray(raw[y * (stride + 1) + 1:(y + 1) * (stride + 1)])
        for i in range(stride):
            a = line[i - bpp] if i >= bpp else 0
            b = prev[i]
            c = prev[i - bpp] if i >= bpp else 0
            if f == 1:
                line[i] = (line[i] + a) & 255
            elif f == 2:
                line[i] = (line[i] + b) & 255
            elif f == 3:
                line[i] = (line[i] + (a + b) // 2) & 255
            elif f == 4:
                line[i] = (line[i] + paeth(a, b, c)) & 255
            elif f != 0:
                fail("%s: unknown filter %d" % (path, f))
        rows.append(bytes(line))
        prev = line
    return width, height, rows


def read_numbers(path):
    for line in open(path):
        line = line.split("#")[0].split()
        if line:
            yield line


def boundary_faces(ele_path):
    """The triangles that belong to exactly one tet (as vertex triples, 0-based)."""
    lines = list(read_numbers(ele_path))
    count = {}
    for fields in lines[1:int(lines[0][0]) + 1]:
        t = [int(v) for v in fields[1:5]]
        for f in ((t[1], t[2], t[3]), (t[0], t[2], t[3]), (t[0], t[1], t[3]), (t[0], t[1], t[2])):
            key = tuple(sorted(f))
            count[key] = count.get(key, 0) + 1
    return [f for f, n in count.items() if n == 1]


def cover(tri, covered):
    """Adds the pixels whose centres lie inside the screen triangle `tri` to `covered`."""
    (x0, y0), (x1, y1), (x2, y2) = tri
    area = (x1 - x0) * (y2 - y0) - (y1 - y0) * (x2 - x0)
    if area == 0:
        return
    for py in range(max(0, int(min(y0, y1, y2))), min(HEIGHT, int(max(y0, y1, y2)) + 1)):
        cy = py + 0.5
        for px in range(max(0, int(min(x0, x1, x2))), min(WIDTH, int(max(x0, x1, x2)) + 1)):
            cx = px + 0.5
            w0 = ((x2 - x1) * (cy - y1) - (y2 - y1) * (cx - x1)) / area
            w1 = ((x0 - x2) * (cy - y2) - (y0 - y2) * (cx - x2)) / area
            w2 = ((x1 - x0) * (cy - y0) - (y1 - y0) * (cx - x0)) / area
            if w0 >= 0 and w1 >= 0 and w2 >= 0:
                covered.add((px, py))


def main():
    simit, scene, node, outdir, frames = sys.argv[1:6]
    os.makedirs(outdir, exist_ok=True)
    final_csv = os.path.join(outdir, "final.csv")
    png = os.path.join(outdir, "bunny.png")
    if os.path.exists(png):
        os.remove(png)
    cmd = [simit, "run", "--frames", frames, "--output", outdir, "--final-csv", final_csv, scene]
    print(" ".join(cmd), flush=True)
    if subprocess.call(cmd) != 0:
        fail("simit run failed")
    width, height, rows = decode_png(png)
    if (width, height) != (WIDTH, HEIGHT):
        fail("the picture is %d x %d, expected %d x %d" % (width, height, WIDTH, HEIGHT))
    pixel = lambda x, y: rows[y][3 * x:3 * x + 3]
    background = pixel(0, 0)
    if min(background) < 230:
        fail("the background %r is not white-ish" % (tuple(background),))
    for x, y in ((WIDTH - 1, 0), (0, HEIGHT - 1), (WIDTH - 1, HEIGHT - 1)):
        if pixel(x, y) != background:
            fail("corner (%d, %d) is not the background" % (x, y))
    ink = {(x, y) for y in range(HEIGHT) for x in range(WIDTH) if pixel(x, y) != background}
    fraction = len(ink) / (WIDTH * HEIGHT)
    colours = len({pixel(x, y) for x, y in ink})
    print("non-background pixels: %.4f of the picture, %d colours" % (fraction, colours))
    if not INK_FRACTION[0] <= fraction <= INK_FRACTION[1]:
        fail("non-background fraction %.4f outside [%g, %g]" % ((fraction,) + INK_FRACTION))
    if colours < 50:
        fail("only %d colours: the surface is not shaded" % colours)

    # The bounding box against the projected positions of the last frame.
    points = [tuple(float(v) for v in line.split(",")) for line in open(final_csv).readlines()[1:]]
    uv = [((x - z) / math.sqrt(2), (-x + 2 * y - z) / math.sqrt(6)) for x, y, z in points]
    u0, u1 = min(p[0] for p in uv), max(p[0] for p in uv)
    v0, v1 = min(p[1] for p in uv), max(p[1] for p in uv)
    x0, x1 = min(p[0] for p in ink), max(p[0] for p in ink) + 1
    y0, y1 = min(p[1] for p in ink), max(p[1] for p in ink) + 1
    aspect, expected = (x1 - x0) / (y1 - y0), (u1 - u0) / (v1 - v0)
    print("ink box %d..%d x %d..%d: aspect %.4f, projected bunny %.4f" % (x0, x1, y0, y1, aspect, expected))
    if abs(aspect / expected - 1) > 0.02:
        fail("the picture's aspect ratio %.4f is not the bunny's %.4f" % (aspect, expected))
    if abs((x0 + x1) / 2 - WIDTH / 2) > 2 or abs((y0 + y1) / 2 - HEIGHT / 2) > 2:
        fail("the bunny is not centred")
    if max((x1 - x0) / WIDTH, (y1 - y0) / HEIGHT) < 0.9:
        fail("the bunny does not fill the picture along either side")

    # The silhouette: scan-convert the projected boundary faces with the box's scale.
    s = ((x1 - x0) / (u1 - u0) + (y1 - y0) / (v1 - v0)) / 2
    screen = [(x0 + (u - u0) * s, y0 + (v1 - v) * s) for u, v in uv]
    covered = set()
    ele = os.path.splitext(node)[0] + ".ele"
    for f in boundary_faces(ele):
        cover([screen[i] for i in f], covered)
    iou = len(ink & covered) / len(ink | covered)
    print("silhouette: %d pixels drawn, %d expected, intersection over union %.4f"
          % (len(ink), len(covered), iou))
    if iou < MIN_IOU:
        fail("the silhouette differs from the bunny's (IoU %.4f < %g)" % (iou, MIN_IOU))
    print("ok: the picture shows the bunny")


main()
