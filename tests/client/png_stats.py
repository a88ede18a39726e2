#!/usr/bin/env python3
"""png_stats.py — what a screenshot holds, with the standard library only (zlib, no PIL).

    png_stats.py FILE.png                    prints "WIDTHxHEIGHT colours=N ink=F"
    png_stats.py FILE.png --crop X Y W H OUT writes that rectangle as OUT.png (for looking at)

Reads 8-bit non-interlaced PNGs of colour type 2 (RGB) or 6 (RGBA), which is what Chromium's
--screenshot writes: the IDAT chunks are inflated and every scanline's filter (None, Sub, Up,
Average, Paeth; PNG spec §9) undone. "colours" counts the distinct RGB values; "ink" is the
fraction of pixels that are not near-white (any channel below 235), so a page that drew nothing
but its background has colours = 1 and ink = 0.
"""
import struct
import sys
import zlib


def read_png(path):
    with open(path, 'rb') as f:
        data = f.read()
    if data[:8] != b'\x89PNG\r\n\x1a\n':
        raise ValueError(f'{path}: not a PNG file')
    pos, idat, header = 8, [], None
    while pos + 8 <= len(data):
        length, kind = struct.unpack('>I4s', data[pos:pos + 8])
        body = data[pos + 8:pos + 8 + length]
        if kind == b'IHDR':
            header = struct.unpack('>IIBBBBB', body)
        elif kind == b'IDAT':
            idat.append(body)
        elif kind == b'IEND':
            break
        pos += 12 + length
    if header is None:
        raise ValueError(f'{path}: no IHDR chunk')
    width, height, depth, ctype, _, _, interlace = header
    if depth != 8 or ctype not in (2, 6) or interlace != 0:
        raise ValueError(f'{path}: unsupported PNG (depth {depth}, colour type {ctype}, '
                         f'interlace {interlace})')
    bpp = 3 if ctype == 2 else 4
    raw = zlib.decompress(b''.join(idat))
    stride = width * bpp
    rows, prev = [], bytearray(stride)
    for y in range(height):
        ftype = raw[y * (stride + 1)]
        line = bytearray(raw[y * (stride + 1) + 1:(y + 1) * (stride + 1)])
        if ftype == 1:
            for i in range(bpp, stride):
                line[i] = (line[i] + line[i - bpp]) & 255
        elif ftype == 2:
            for i in range(stride):
                line[i] = (line[i] + prev[i]) & 255
        elif ftype == 3:
            for i in range(stride):
                left = line[i - bpp] if i >= bpp else 0
                line[i] = (line[i] + ((left + prev[i]) >> 1)) & 255
        elif ftype == 4:
            for i in range(stride):
                a = line[i - bpp] if i >= bpp else 0
                b = prev[i]
                c = prev[i - bpp] if i >= bpp else 0
                p = a + b - c
                pa, pb, pc = abs(p - a), abs(p - b), abs(p - c)
                pred = a if pa <= pb and pa <= pc else (b if pb <= pc else c)
                line[i] = (line[i] + pred) & 255
        elif ftype != 0:
            raise ValueError(f'{path}: bad filter {ftype} on row {y}')
        rows.append(bytes(line))
        prev = line
    return width, height, bpp, rows


def write_png(path, width, height, rows_rgb):
    def chunk(kind, body):
        return (struct.pack('>I', len(body)) + kind + body +
                struct.pack('>I', zlib.crc32(kind + body) & 0xffffffff))
    raw = b''.join(b'\x00' + r for r in rows_rgb)
    with open(path, 'wb') as f:
        f.write(b'\x89PNG\r\n\x1a\n')
        f.write(chunk(b'IHDR', struct.pack('>IIBBBBB', width, height, 8, 2, 0, 0, 0)))
        f.write(chunk(b'IDAT', zlib.compress(raw, 6)))
        f.write(chunk(b'IEND', b''))


def main(argv):
    if len(argv) not in (2, 8) or (len(argv) == 8 and argv[2] != '--crop'):
        print(__doc__.strip().split('\n\n')[1], file=sys.stderr)
        return 2
    width, height, bpp, rows = read_png(argv[1])
    if len(argv) == 8:
        x, y, w, h = (int(v) for v in argv[3:7])
        w, h = min(w, width - x), min(h, height - y)
        out = [bytes(b for i in range(x, x + w) for b in rows[r][i * bpp:i * bpp + 3])
               for r in range(y, y + h)]
        write_png(argv[7], w, h, out)
        return 0
    colours, ink = set(), 0
    for r in rows:
        for i in range(0, width * bpp, bpp):
            px = r[i:i + 3]
            colours.add(px)
            if min(px) < 235:
                ink += 1
    print(f'{width}x{height} colours={len(colours)} ink={ink / (width * height):.4f}')
    return 0


if __name__ == '__main__':
    sys.exit(main(sys.argv))
