#!/usr/bin/env python3
"""Prints the RGB values of pbrt-v4's named spectra that src/scene/loader/spectra.rs holds.

Usage: scripts/named_spectra.py PBRT_V4/src/pbrt/util/spectrum.cpp

The method (pbrt-v3's `SampledSpectrum::ToRGB`, which is where the widely published RGB values of
copper, gold, silver and aluminium come from):

- each named spectrum is pbrt-v4's `PiecewiseLinearSpectrum` over its (wavelength, value) table,
  0 outside the table's range;
- XYZ = sum over 360..830 nm at 1 nm of s(l) * (xbar, ybar, zbar)(l), divided by the sum of ybar,
  with the CIE 1931 2-degree matching functions tabulated in the same spectrum.cpp;
- linear sRGB = the IEC 61966-2-1 XYZ-to-sRGB matrix times XYZ (no white balance: a constant
  spectrum 1 gives (1.2049, 0.9482, 0.9092)).

Glasses (`glass-*`, dielectric `eta`) are the spectrum's value at 550 nm.
"""
import re
import sys

SRC = open(sys.argv[1]).read()
XYZ_TO_SRGB = [[3.2404542, -1.5371385, -0.4985314],
               [-0.9692660, 1.8760108, 0.0415560],
               [0.0556434, -0.2040259, 1.0572252]]
METALS = ["Ag", "Al", "Au", "Cu", "CuZn", "MgO", "TiO2"]
GLASSES = [("BK7", "BK7"), ("BAF10", "BAF10"), ("FK51A", "FK51A"), ("LASF9", "LASF9"),
           ("F5", "SF5"), ("F10", "SF10"), ("F11", "SF11")]


def array(name):
    m = re.search(r"const Float %s\[[^\]]*\] = \{(.*?)\};" % re.escape(name), SRC, re.S)
    return [float(x) for x in re.findall(r"[-+]?\d*\.?\d+(?:[eE][-+]?\d+)?", m.group(1))]


def piecewise_linear(data):
    xs, ys = data[0::2], data[1::2]

    def f(l):
        if l < xs[0] or l > xs[-1]:
            return 0.0
        for i in range(len(xs) - 1):
            if xs[i] <= l <= xs[i + 1]:
                t = (l - xs[i]) / (xs[i + 1] - xs[i])
                return ys[i] * (1 - t) + ys[i + 1] * t
        return ys[-1]
    return f


LAMBDA, CMF = array("CIE_lambda"), [array("CIE_X"), array("CIE_Y"), array("CIE_Z")]
assert len(LAMBDA) == 471 and LAMBDA[0] == 360 and LAMBDA[-1] == 830


def to_rgb(f):
    s = [f(l) for l in LAMBDA]
    xyz = [sum(a * b for a, b in zip(s, c)) / sum(CMF[1]) for c in CMF]
    return [sum(XYZ_TO_SRGB[r][c] * xyz[c] for c in range(3)) for r in range(3)]


def num(v):
    """Six decimals without trailing zeros, as Rust source."""
    s = ("%.6f" % v).rstrip("0")
    return s + "0" if s.endswith(".") else s


for metal in METALS:
    for part in ["eta", "k"]:
        r, g, b = (max(v, 0.0) for v in to_rgb(piecewise_linear(array("%s_%s" % (metal, part)))))
        print('    ("metal-%s-%s", Vec3::new(%s, %s, %s)),' % (metal, part, num(r), num(g), num(b)))
for name, table in GLASSES:
    print('    ("glass-%s", %s),' % (name, num(piecewise_linear(array("Glass%s_eta" % table))(550.0))))
