#!/usr/bin/env python3
"""Prints the CIE 1931 2-degree colour matching functions at 5 nm, 360..830 nm, as the Rust table
in src/scene/loader/blackbody.rs.

Usage: scripts/cie_table.py PBRT_V4/src/pbrt/util/spectrum.cpp

Source: the CIE 1931 standard observer as pbrt-v4 tabulates it at 1 nm (`CIE_lambda`, `CIE_X`,
`CIE_Y`, `CIE_Z` in spectrum.cpp; CIE 015:2004, table T.4), every fifth row (the CIE's own
5 nm table is the same rows).
"""
import re
import sys

SRC = open(sys.argv[1]).read()


def array(name):
    m = re.search(r"const Float %s\[[^\]]*\] = \{(.*?)\};" % re.escape(name), SRC, re.S)
    return [float(x) for x in re.findall(r"[-+]?\d*\.?\d+(?:[eE][-+]?\d+)?", m.group(1))]


LAMBDA = array("CIE_lambda")
X, Y, Z = array("CIE_X"), array("CIE_Y"), array("CIE_Z")
assert len(LAMBDA) == 471 and LAMBDA[0] == 360 and LAMBDA[-1] == 830
rows = [i for i in range(471) if int(LAMBDA[i]) % 5 == 0]
print("pub const CIE_XYZ_5NM: [[f32; 3]; %d] = [" % len(rows))
for i in rows:
    print("    [%s, %s, %s], // %d nm" % (repr(X[i]), repr(Y[i]), repr(Z[i]), LAMBDA[i]))
print("];")
