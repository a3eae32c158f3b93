#!/usr/bin/env python3
"""Writes scenes/textures/sky-64.pfm: a 64x64 sky in pbrt-v4's equal-area octahedral
parameterisation (light frame: +z up), for scenes/envlight-sky.pbrt.

Upper hemisphere: a sky from a pale horizon to a deeper zenith blue plus a sun (radiance 150,
4 degrees in radius, 35 degrees above the horizon towards +x); lower hemisphere: dim ground
reached over 15 degrees below the horizon.
The square -> sphere map is written out here from Clarberg's construction (as pbrt-v4's
EqualAreaSquareToSphere), independently of photon's Rust code, and each texel takes the value at
its centre. Usage: python3 scripts/make_sky.py [N]
"""
import math
import struct
import sys


def square_to_sphere(u, v):
    u, v = 2 * u - 1, 2 * v - 1
    up, vp = abs(u), abs(v)
    signed = 1 - (up + vp)
    r = 1 - abs(signed)
    phi = (1 if r == 0 else (vp - up) / r + 1) * math.pi / 4
    z = math.copysign(1 - r * r, signed)
    s = r * math.sqrt(max(0.0, 2 - r * r))
    return (math.copysign(math.cos(phi), u) * s, math.copysign(math.sin(phi), v) * s, z)


HORIZON = (0.9, 0.95, 1.0)
ZENITH = (0.25, 0.45, 0.9)
GROUND = (0.12, 0.1, 0.08)


def mix(a, b, t):
    return [p * (1 - t) + q * t for p, q in zip(a, b)]


def radiance(w):
    x, y, z = w
    if z < 0:
        # Fades into the ground over 15 degrees below the horizon (a sharp horizon would
        # show the texel staircase of a small map).
        return tuple(mix(HORIZON, GROUND, min(1.0, -z / math.sin(math.radians(15)))))
    sky = mix(HORIZON, ZENITH, z ** 0.5)
    e = math.radians(35)
    sun = (math.cos(e), 0.0, math.sin(e))
    if x * sun[0] + y * sun[1] + z * sun[2] > math.cos(math.radians(4)):
        sky = [c + 150 * k for c, k in zip(sky, (1.0, 0.9, 0.75))]
    return tuple(sky)


def main():
    n = int(sys.argv[1]) if len(sys.argv) > 1 else 64
    out = bytearray(b"PF\n%d %d\n-1.0\n" % (n, n))
    # PFM rows run bottom-up; image row 0 (v near 0) is the top of the picture.
    for row in reversed(range(n)):
        for col in range(n):
            w = square_to_sphere((col + 0.5) / n, (row + 0.5) / n)
            out += struct.pack("<3f", *radiance(w))
    path = "scenes/textures/sky-%d.pfm" % n
    with open(path, "wb") as f:
        f.write(out)
    print("wrote", path)


if __name__ == "__main__":
    main()
