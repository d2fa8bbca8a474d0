#!/usr/bin/env python3
"""Print Mitsuba 3's BSDF values at fixed directions, as the rows of the `MITSUBA_REFERENCE`
table of crates/raytracer/src/integrator/bsdfs/tests.rs (which compares rayterra's BSDFs with
them).

Usage: bsdf_reference.py > rows.rs   (with Mitsuba 3.9.1, as .ci/run installs it in
target/mitsuba-venv: target/mitsuba-venv/bin/python tools/mitsuba/bsdf_reference.py)

Each row: (name, wo, wi, f, pdf), wo and wi as (theta, phi) in degrees in the local frame
(+z the normal), f = Mitsuba's `eval` divided by |cos wi| (rayterra's eval has no cosine), pdf
= Mitsuba's `pdf`; Mitsuba's `si.wi` is rayterra's `wo`. Variant `scalar_rgb`.
"""

import math

import mitsuba as mi

mi.set_variant("scalar_rgb")

GOLD = {
    "eta": {"type": "rgb", "value": [0.143119, 0.374957, 1.442479]},
    "k": {"type": "rgb", "value": [3.983160, 2.385721, 1.603215]},
}
BASE = {"type": "rgb", "value": [0.5, 0.7, 0.2]}

# Keep in step with `mitsuba_material` in tests.rs.
CASES = {
    "roughconductor_ggx": {"type": "roughconductor", "distribution": "ggx", "alpha_u": 0.2, "alpha_v": 0.4, **GOLD},
    "roughconductor_beckmann": {"type": "roughconductor", "distribution": "beckmann", "alpha_u": 0.3, "alpha_v": 0.3, **GOLD},
    "roughdielectric_ggx": {"type": "roughdielectric", "distribution": "ggx", "alpha": 0.3},
    "roughdielectric_beckmann": {"type": "roughdielectric", "distribution": "beckmann", "alpha": 0.5},
    "plastic": {"type": "plastic", "diffuse_reflectance": {"type": "rgb", "value": [0.6, 0.3, 0.1]}},
    "plastic_nl": {"type": "plastic", "diffuse_reflectance": {"type": "rgb", "value": [0.9, 0.9, 0.9]}, "nonlinear": True},
    "roughplastic_ggx": {"type": "roughplastic", "distribution": "ggx", "alpha": 0.3, "diffuse_reflectance": BASE},
    "roughplastic_beckmann": {"type": "roughplastic", "distribution": "beckmann", "alpha": 0.1, "diffuse_reflectance": BASE, "nonlinear": True},
    "diffuse": {"type": "diffuse", "reflectance": {"type": "rgb", "value": [0.8, 0.5, 0.2]}},
    "twosided": {"type": "twosided",
                 "front": {"type": "diffuse", "reflectance": {"type": "rgb", "value": [0.8, 0.5, 0.2]}},
                 "back": {"type": "roughconductor", "distribution": "ggx", "alpha_u": 0.2, "alpha_v": 0.4, **GOLD}},
    "mask": {"type": "mask", "opacity": 0.3,
             "bsdf": {"type": "roughplastic", "distribution": "ggx", "alpha": 0.3, "diffuse_reflectance": BASE}},
    "blend": {"type": "blendbsdf", "weight": 0.3,
              "bsdf_0": {"type": "diffuse", "reflectance": {"type": "rgb", "value": [0.8, 0.5, 0.2]}},
              "bsdf_1": {"type": "roughdielectric", "distribution": "ggx", "alpha": 0.3}},
    "principled_default": {"type": "principled"},
    "principled_full": {"type": "principled", "base_color": {"type": "rgb", "value": [0.8, 0.3, 0.1]},
                        "metallic": 0.3, "specular": 0.6, "roughness": 0.3, "spec_tint": 0.4,
                        "anisotropic": 0.5, "sheen": 0.3, "sheen_tint": 0.2, "clearcoat": 0.6,
                        "clearcoat_gloss": 0.3, "flatness": 0.4},
    "principled_glass": {"type": "principled", "base_color": {"type": "rgb", "value": [0.9, 0.8, 0.7]},
                         "spec_trans": 0.8, "eta": 1.4, "roughness": 0.4, "metallic": 0.1, "sheen": 0.5},
    "principled_metal": {"type": "principled", "base_color": {"type": "rgb", "value": [0.9, 0.6, 0.2]},
                         "metallic": 1.0, "roughness": 0.2, "anisotropic": 0.3},
    "principledthin_default": {"type": "principledthin"},
    "principledthin_full": {"type": "principledthin", "base_color": {"type": "rgb", "value": [0.7, 0.1, 0.1]},
                            "roughness": 0.3, "spec_tint": 0.1, "anisotropic": 0.5, "spec_trans": 0.6,
                            "diff_trans": 0.6, "eta": 1.33, "sheen": 0.5, "sheen_tint": 0.5, "flatness": 0.3},
    "principledthin_clear": {"type": "principledthin", "spec_trans": 0.9, "eta": 1.5, "roughness": 0.4},
}

# Delta BSDFs: `sample` at fixed numbers, (name, wo, sample1) -> (wi, weight, pdf, eta).
DELTA = {
    "dielectric": {"type": "dielectric"},
    "thindielectric": {"type": "thindielectric"},
    "conductor": {"type": "conductor", **GOLD},
    "plastic": {"type": "plastic", "diffuse_reflectance": {"type": "rgb", "value": [0.6, 0.3, 0.1]}},
}
DELTA_CASES = [((30, 20), 0.01), ((30, 20), 0.9), ((75, 100), 0.05), ((75, 100), 0.6),
               ((150, 40), 0.01), ((150, 40), 0.9), ((120, 200), 0.5)]

PAIRS = [((30, 20), (50, 200)), ((0, 0), (20, 10)), ((60, 120), (140, 300)), ((70, 0), (60, 180)),
         ((150, 40), (30, 250)), ((150, 40), (120, 220))]


def direction(theta, phi):
    t, p = math.radians(theta), math.radians(phi)
    return [math.sin(t) * math.cos(p), math.sin(t) * math.sin(p), math.cos(t)]


def interaction(wo):
    si = mi.SurfaceInteraction3f()
    si.p = [0, 0, 0]
    si.n = [0, 0, 1]
    si.sh_frame = mi.Frame3f([0, 0, 1])
    si.wi = mi.Vector3f(wo)
    si.uv = [0.5, 0.5]
    return si


ctx = mi.BSDFContext()
for name, spec in CASES.items():
    bsdf = mi.load_dict(spec)
    for wo, wi in PAIRS:
        si = interaction(direction(*wo))
        w = direction(*wi)
        value = bsdf.eval(ctx, si, mi.Vector3f(w))
        pdf = bsdf.pdf(ctx, si, mi.Vector3f(w))
        f = [value[i] / abs(w[2]) for i in range(3)]
        print(f'    ("{name}", ({wo[0]:.1f}, {wo[1]:.1f}), ({wi[0]:.1f}, {wi[1]:.1f}), '
              f"[{f[0]:.7e}, {f[1]:.7e}, {f[2]:.7e}], {pdf:.7e}),")

print("// delta")
for name, spec in DELTA.items():
    bsdf = mi.load_dict(spec)
    for wo, u in DELTA_CASES:
        si = interaction(direction(*wo))
        bs, weight = bsdf.sample(ctx, si, u, mi.Point2f(0.5, 0.5))
        if bs.pdf == 0 or not mi.has_flag(bs.sampled_type, mi.BSDFFlags.Delta):
            print(f'    ("{name}", ({wo[0]:.1f}, {wo[1]:.1f}), {u}, None),')
            continue
        w = bs.wo
        print(f'    ("{name}", ({wo[0]:.1f}, {wo[1]:.1f}), {u}, Some(([{w[0]:.9e}, {w[1]:.9e}, {w[2]:.9e}], '
              f"[{weight[0]:.7e}, {weight[1]:.7e}, {weight[2]:.7e}], {bs.pdf:.7e}, {bs.eta:.7e}))),")
