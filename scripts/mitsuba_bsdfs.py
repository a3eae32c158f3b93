#!/usr/bin/env python3
"""Evaluates Mitsuba 3's `roughdielectric` (GGX, visible-normal sampling), `roughconductor` (GGX,
gold) and `thindielectric` at a fixed set of direction pairs and writes scenes/mitsuba/bsdfs.json,
the independent values that src/bsdf/dielectric.rs, conductor.rs and thin_dielectric.rs compare
against.

Run with a Python that has `pip install mitsuba` (the scalar_rgb variant needs no LLVM):

    python3 scripts/mitsuba_bsdfs.py scenes/mitsuba/bsdfs.json

Conventions: Mitsuba's `si.wi` is photon's `wo` (towards the viewer) and Mitsuba's `wo` is
photon's `wi`; `eval` returns f * |cos wi|. Mitsuba uses the separable Smith G1(wo) G1(wi),
pbrt-v4 (and photon) the height-correlated 1 / (1 + Lambda(wo) + Lambda(wi)); the file
therefore also records Mitsuba's G1 of both directions about the half vector, so the test can
convert Mitsuba's value without using photon's own masking function.
"""
import json
import math
import sys

import mitsuba as mi

mi.set_variant("scalar_rgb")

ETA = 1.5


def unit(theta, phi, below=False):
    z = math.cos(theta)
    v = [math.sin(theta) * math.cos(phi), math.sin(theta) * math.sin(phi), -z if below else z]
    return v


def half_vector(wo, wi, eta):
    """Mitsuba's generalized half vector (wo is Mitsuba's si.wi), turned to +z."""
    reflect = wo[2] * wi[2] > 0
    e = 1.0 if reflect else (eta if wo[2] > 0 else 1.0 / eta)
    m = [wo[k] + wi[k] * e for k in range(3)]
    n = math.sqrt(sum(c * c for c in m))
    m = [c / n for c in m]
    if m[2] < 0:
        m = [-c for c in m]
    return m


def rough_dielectric_rows():
    rows = []
    frame = mi.Frame3f(mi.Vector3f(1, 0, 0), mi.Vector3f(0, 1, 0), mi.Vector3f(0, 0, 1))
    for au, av in [(0.1, 0.1), (0.3, 0.3), (0.6, 0.6), (0.2, 0.5)]:
        bsdf = mi.load_dict({
            "type": "roughdielectric", "distribution": "ggx", "alpha_u": au, "alpha_v": av,
            "int_ior": ETA, "ext_ior": 1.0, "sample_visible": True,
        })
        distr = mi.MicrofacetDistribution(mi.MicrofacetType.GGX, au, av, True)
        pairs = []
        for to, po, bo in [(0.3, 0.2, False), (1.0, 1.1, False), (0.5, 2.0, True), (1.2, 4.0, True)]:
            for ti, pi_, bi in [(0.4, 3.5, False), (0.9, 3.0, False), (0.2, 2.9, True),
                                (0.6, 3.3, True), (1.3, 0.5, True), (0.7, 5.0, False)]:
                pairs.append((unit(to, po, bo), unit(ti, pi_, bi)))
        for wo, wi in pairs:
            si = mi.SurfaceInteraction3f()
            si.sh_frame = frame
            si.wi = mi.Vector3f(wo)
            for mode_name, mode in [("radiance", mi.TransportMode.Radiance),
                                    ("importance", mi.TransportMode.Importance)]:
                ctx = mi.BSDFContext(mode)
                val = bsdf.eval(ctx, si, mi.Vector3f(wi))
                pdf = bsdf.pdf(ctx, si, mi.Vector3f(wi))
                m = mi.Vector3f(half_vector(wo, wi, ETA))
                g1o = distr.smith_g1(mi.Vector3f(wo), m)
                g1i = distr.smith_g1(mi.Vector3f(wi), m)
                rows.append({
                    "alpha_u": au, "alpha_v": av, "eta": ETA, "mode": mode_name,
                    "wo": wo, "wi": wi, "f_cos": float(val[1]), "pdf": float(pdf),
                    "g1_wo": float(g1o), "g1_wi": float(g1i),
                })
    return rows


GOLD_ETA = [0.143, 0.374, 1.442]
GOLD_K = [3.983, 2.385, 1.603]


def rough_conductor_rows():
    rows = []
    frame = mi.Frame3f(mi.Vector3f(1, 0, 0), mi.Vector3f(0, 1, 0), mi.Vector3f(0, 0, 1))
    ctx = mi.BSDFContext()
    for au, av in [(0.1, 0.1), (0.4, 0.4), (0.2, 0.6)]:
        bsdf = mi.load_dict({
            "type": "roughconductor", "distribution": "ggx", "alpha_u": au, "alpha_v": av,
            "eta": {"type": "rgb", "value": GOLD_ETA}, "k": {"type": "rgb", "value": GOLD_K},
            "sample_visible": True,
        })
        distr = mi.MicrofacetDistribution(mi.MicrofacetType.GGX, au, av, True)
        for to, po in [(0.2, 0.3), (0.9, 1.5), (1.35, 4.0)]:
            for ti, pi_ in [(0.1, 3.3), (0.5, 3.0), (1.0, 4.4), (1.4, 0.2)]:
                wo, wi = unit(to, po), unit(ti, pi_)
                si = mi.SurfaceInteraction3f()
                si.sh_frame = frame
                si.wi = mi.Vector3f(wo)
                val = bsdf.eval(ctx, si, mi.Vector3f(wi))
                m = mi.Vector3f(half_vector(wo, wi, 1.0))
                rows.append({
                    "alpha_u": au, "alpha_v": av, "eta": GOLD_ETA, "k": GOLD_K,
                    "wo": wo, "wi": wi, "f_cos": [float(val[c]) for c in range(3)],
                    "pdf": float(bsdf.pdf(ctx, si, mi.Vector3f(wi))),
                    "g1_wo": float(distr.smith_g1(mi.Vector3f(wo), m)),
                    "g1_wi": float(distr.smith_g1(mi.Vector3f(wi), m)),
                })
    return rows


def thin_dielectric_rows():
    rows = []
    bsdf = mi.load_dict({"type": "thindielectric", "int_ior": ETA, "ext_ior": 1.0})
    ctx = mi.BSDFContext(mi.TransportMode.Radiance)
    for theta in [0.0, 0.3, 0.7, 1.0, 1.3, 1.5]:
        for below in [False, True]:
            wo = unit(theta, 0.4, below)
            si = mi.SurfaceInteraction3f()
            si.wi = mi.Vector3f(wo)
            refl, w_r = bsdf.sample(ctx, si, 0.0, mi.Point2f(0.5, 0.5))
            trans, w_t = bsdf.sample(ctx, si, 0.999999, mi.Point2f(0.5, 0.5))
            rows.append({
                "eta": ETA, "wo": wo,
                "reflect_pdf": float(refl.pdf), "reflect_wi": [float(c) for c in refl.wo],
                "reflect_weight": float(w_r[1]),
                "transmit_pdf": float(trans.pdf), "transmit_wi": [float(c) for c in trans.wo],
                "transmit_weight": float(w_t[1]),
            })
    return rows


def main():
    out = sys.argv[1] if len(sys.argv) > 1 else "scenes/mitsuba/bsdfs.json"
    data = {
        "generator": f"scripts/mitsuba_bsdfs.py, Mitsuba {mi.__version__} scalar_rgb",
        "roughdielectric": rough_dielectric_rows(),
        "roughconductor": rough_conductor_rows(),
        "thindielectric": thin_dielectric_rows(),
    }
    with open(out, "w") as f:  # one row per line
        f.write("{\n" + f' "generator": {json.dumps(data["generator"])}')
        for key in ["roughdielectric", "roughconductor", "thindielectric"]:
            rows = ",\n  ".join(json.dumps(r) for r in data[key])
            f.write(f',\n "{key}": [\n  {rows}\n ]')
        f.write("\n}\n")
    counts = ", ".join(f"{len(data[k])} {k}" for k in data if k != "generator")
    print(f"wrote {out}: {counts}")


if __name__ == "__main__":
    main()
