#!/usr/bin/env python3
"""Half-size PNG preview of a PFM image for the README: 2x2 box average, divided by the 0.99 quantile of
all channel values (as dartspp's own previews), clamped, sRGB. Standard library only.
usage: bench/half_png.py IMAGE.pfm OUT.png"""
import struct, sys, zlib

def read_pfm(path):
    with open(path, 'rb') as f:
        kind = f.readline().strip()
        w, h = map(int, f.readline().split())
        scale = float(f.readline())
        n = 3 if kind == b'PF' else 1
        data = struct.unpack(('<' if scale < 0 else '>') + 'f' * (w * h * n), f.read(4 * w * h * n))
    rows = [data[(h - 1 - y) * w * n:(h - y) * w * n] for y in range(h)]  # PFM rows run bottom to top
    return w, h, n, rows

def srgb(v):
    v = min(max(v, 0.0), 1.0)
    return 12.92 * v if v <= 0.0031308 else 1.055 * v ** (1 / 2.4) - 0.055

def main():
    w, h, n, rows = read_pfm(sys.argv[1])
    hw, hh = w // 2, h // 2
    small = [[sum(rows[2 * y + dy][(2 * x + dx) * n + (c if n == 3 else 0)] for dy in (0, 1) for dx in (0, 1)) / 4
              for x in range(hw) for c in range(3)] for y in range(hh)]
    vals = sorted(v for r in small for v in r)
    q = vals[int(0.99 * (len(vals) - 1))] or 1.0
    raw = b''.join(b'\0' + bytes(int(round(255 * srgb(v / q))) for v in r) for r in small)
    chunk = lambda t, d: struct.pack('>I', len(d)) + t + d + struct.pack('>I', zlib.crc32(t + d) & 0xffffffff)
    png = b'\x89PNG\r\n\x1a\n' + chunk(b'IHDR', struct.pack('>IIBBBBB', hw, hh, 8, 2, 0, 0, 0)) + \
        chunk(b'IDAT', zlib.compress(raw, 9)) + chunk(b'IEND', b'')
    open(sys.argv[2], 'wb').write(png)

main()
