#!/usr/bin/env python3
"""Render a rayterra scene file with Mitsuba 3, as rayterra's physically based models read it.

This is a check of rayterra, not a part of it: the same scene, converted key by key to Mitsuba 3's
plugins (variant `scalar_rgb`, or `llvm_ad_rgb` with `--variant`), rendered by Mitsuba's own `path` integrator (`volpath` when a glass
absorbs), so that rayterra's `--model path` and `--model sppm` can be compared with a renderer the
field trusts. The reading of every key is the one in rayterra's docs/raytracer-models.md ("How it renders"):

- camera: `perspective` (or `thinlens` for `aperture=`), field of view from `lens_W`, box pixel
  filter; the thin lens focuses at `focal_dist=`, or on the surface seen at the image centre;
- `light point`: `point` of intensity `color`; `light square`: two back-to-back one-sided
  rectangles (both faces emit radiance `color`) with black surfaces; `light sphere`: a sphere
  area emitter of radiance `color` with a black surface;
- background: a `constant` emitter of radiance `color`, or an `envmap` holding the `top=`/`bottom=`
  gradient (rotated so that its up is +z);
- `sphere`, `square` (a `rectangle` through an affine map), `plane` (a rectangle of half size
  `PLANE_HALF_SIZE` centred under the camera), `cylinder` (Mitsuba's open `cylinder` plus two
  `disk` caps);
- materials: the weights `diff`, `spec`, `refl`, `refr` normalised to a sum of at most 1, mixed with
  nested `blendbsdf`s (with a black `diffuse` for the absorbed rest): `diffuse`, `roughconductor`
  (GGX, `material= none`) of alpha `sqrt(2 / 22)` for `spec` and `drefl / 4` for a glossy `refl`,
  `conductor` (`material= none`) for a mirror, `dielectric` of index `rindex` for `refr`, all tinted
  by `color` except the dielectric; two-sided (`twosided`) unless the material refracts; `absor=`
  becomes a purely absorbing `homogeneous` interior medium.

Textures are not converted (the tool refuses textured scenes), nor are spheres of radius 1e4 or more
(Mitsuba's single precision cannot hit them exactly; write walls as squares or planes).

Usage:
    python tools/mitsuba/rayterra_mitsuba.py SCENE -o OUT.exr [--size WxH] [--spp N]
        [--max-depth N] [--seed N] [--threads N] [--variant scalar_rgb|llvm_ad_rgb]

`--variant llvm_ad_rgb` is Mitsuba's vectorised CPU backend (Dr.Jit compiles the integrator into
one kernel); it needs LLVM (`apt-get install libllvm19` and
`DRJIT_LIBLLVM_PATH=/usr/lib/x86_64-linux-gnu/libLLVM.so.19.1`). Its render time is measured up to
the finished image (`dr.eval` and `dr.sync_thread`), with the kernel cache as it is: run it once
first to time it warm.
It prints one line: `mitsuba: render <seconds> s, load <seconds> s, <samples> samples`.
"""

import argparse
import math
import sys
import time

SPEC_ALPHA = math.sqrt(2.0 / 22.0)
DREFL_ALPHA_PER_UNIT = 0.25
MIN_ALPHA = 1e-3
PLANE_HALF_SIZE = 1000.0
HUGE_RADIUS = 1e4
GRADIENT_ROWS = 1024


class SceneError(Exception):
    """A scene the tool cannot convert, with the reason."""


def read_text(path):
    data = open(path, "rb").read()
    for encoding in ("utf-8", "gbk"):
        try:
            return data.decode(encoding)
        except UnicodeDecodeError:
            pass
    return data.decode("latin-1")


def strip_comment(line):
    cut = len(line)
    for marker in ("#", "//"):
        i = line.find(marker)
        if i >= 0:
            cut = min(cut, i)
    return line[:cut]


def parse(path):
    """The blocks of a scene file: a list of (kind, type, {key: [values]}), later keys winning."""
    blocks = []
    current = None
    for number, raw in enumerate(read_text(path).splitlines(), 1):
        words = strip_comment(raw).split()
        if not words:
            continue
        head = words[0]
        if current is None:
            if head in ("background", "camera"):
                current = (head, None, {})
            elif head in ("light", "primitive", "obj") and len(words) >= 2:
                current = ("primitive" if head == "obj" else head, words[1], {})
            else:
                raise SceneError(f"{path}:{number}: unexpected `{head}` outside a block")
            continue
        if head == "end":
            blocks.append(current)
            current = None
            continue
        if not head.endswith("="):
            raise SceneError(f"{path}:{number}: expected `key= value`, found `{head}`")
        current[2][head[:-1]] = words[1:]
    if current is not None:
        raise SceneError(f"{path}: block `{current[0]}` has no `end`")
    return blocks


def vec(keys, key, default=None):
    if key not in keys:
        if default is None:
            raise SceneError(f"missing `{key}=`")
        return list(default)
    values = [float(v) for v in keys[key]]
    if len(values) != 3:
        raise SceneError(f"`{key}=` expects 3 numbers")
    return values


def num(keys, key, default=None):
    if key not in keys:
        if default is None:
            raise SceneError(f"missing `{key}=`")
        return default
    return float(keys[key][0])


def sub(a, b):
    return [a[i] - b[i] for i in range(3)]


def add(a, b):
    return [a[i] + b[i] for i in range(3)]


def scale(a, s):
    return [x * s for x in a]


def dot(a, b):
    return sum(a[i] * b[i] for i in range(3))


def cross(a, b):
    return [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]]


def normalize(a):
    length = math.sqrt(dot(a, a))
    if length == 0:
        raise SceneError("a zero vector")
    return scale(a, 1.0 / length)


def basis(n):
    """Two unit vectors t, b with (t, b, n) right-handed and orthonormal (as rayterra's)."""
    sign = math.copysign(1.0, n[2])
    a = -1.0 / (sign + n[2])
    b = n[0] * n[1] * a
    return [1.0 + sign * n[0] * n[0] * a, sign * b, -sign * n[0]], [b, sign + n[1] * n[1] * a, -n[1]]


def affine(mi, x, y, z, origin):
    """The transform whose columns are x, y, z and whose translation is origin."""
    return mi.ScalarTransform4f([
        [x[0], y[0], z[0], origin[0]],
        [x[1], y[1], z[1], origin[1]],
        [x[2], y[2], z[2], origin[2]],
        [0, 0, 0, 1],
    ])


def rgb(values):
    return {"type": "rgb", "value": [max(0.0, float(v)) for v in values]}


BLACK = {"type": "diffuse", "reflectance": {"type": "rgb", "value": [0.0, 0.0, 0.0]}}


def mix(parts):
    """A blend of (weight, bsdf) parts whose weights sum to 1."""
    if len(parts) == 1:
        return parts[0][1]
    (w_last, last), rest = parts[-1], parts[:-1]
    if w_last >= 1.0:
        return last
    rest = [(w / (1.0 - w_last), b) for w, b in rest]
    return {"type": "blendbsdf", "weight": w_last, "bsdf_0": mix(rest), "bsdf_1": last}


def material(keys, state):
    """The BSDF dict of a primitive's material keys, and its interior medium (or None)."""
    if "texture" in keys:
        raise SceneError("textures are not converted; compare untextured scenes")
    color = [min(1.0, max(0.0, c)) for c in vec(keys, "color", [0, 0, 0])]
    w = {k: max(0.0, num(keys, k, 0.0)) for k in ("diff", "spec", "refl", "refr")}
    total = sum(w.values())
    if total > 1.0:
        w = {k: v / total for k, v in w.items()}
    parts = []
    if w["diff"] > 0:
        parts.append((w["diff"], {"type": "diffuse", "reflectance": rgb(color)}))
    if w["spec"] > 0:
        parts.append((w["spec"], {"type": "roughconductor", "material": "none", "distribution": "ggx",
                                   "alpha": SPEC_ALPHA, "specular_reflectance": rgb(color)}))
    if w["refl"] > 0:
        drefl = num(keys, "drefl", 0.0)
        if drefl > 0:
            alpha = min(1.0, max(MIN_ALPHA, drefl * DREFL_ALPHA_PER_UNIT))
            parts.append((w["refl"], {"type": "roughconductor", "material": "none", "distribution": "ggx",
                                      "alpha": alpha, "specular_reflectance": rgb(color)}))
        else:
            parts.append((w["refl"], {"type": "conductor", "material": "none",
                                      "specular_reflectance": rgb(color)}))
    medium = None
    if w["refr"] > 0:
        parts.append((w["refr"], {"type": "dielectric", "int_ior": num(keys, "rindex"), "ext_ior": 1.0}))
        absor = vec(keys, "absor", [0, 0, 0])
        if any(a > 0 for a in absor):
            # Mitsuba reads RGB in [0, 1]: the largest coefficient goes into `scale`.
            peak = max(absor)
            medium = {"type": "homogeneous", "albedo": rgb([0, 0, 0]),
                      "sigma_t": rgb([a / peak for a in absor]), "scale": peak}
            state["media"] = True
    used = sum(p[0] for p in parts)
    if used < 1.0:
        parts.insert(0, (1.0 - used, BLACK))
    bsdf = mix(parts)
    if w["refr"] == 0:
        bsdf = {"type": "twosided", "bsdf": bsdf}
    return bsdf, medium


def convert(mi, path, width=None, height=None, spp=64, max_depth=10, seed=0):
    """The Mitsuba scene dict of a rayterra scene file, and whether it needs `volpath`."""
    blocks = parse(path)
    cam = next((k for kind, _, k in blocks if kind == "camera"), {})
    background = next((k for kind, _, k in blocks if kind == "background"), {})
    width = width or int(num(cam, "image_W", 420))
    height = height or int(num(cam, "image_H", 420))
    eye = vec(cam, "O", [0, 0, 0])
    forward = normalize(vec(cam, "N", [0, 1, 0]))
    right = cross(forward, [0, 0, 1])
    right = normalize(right) if dot(right, right) > 1e-24 else [1, 0, 0]
    up = cross(right, forward)
    lens_w = num(cam, "lens_W", 0.88)
    lens_h = num(cam, "lens_H", 0.88)
    if abs(lens_w / lens_h - width / height) > 0.01 * width / height:
        raise SceneError("lens_W / lens_H differs from the image's aspect; Mitsuba cannot stretch pixels")
    state = {"media": False}
    scene = {"type": "scene"}
    for index, (kind, typ, keys) in enumerate(blocks):
        name = f"{kind}_{index}"
        try:
            if kind == "light":
                color = vec(keys, "color", [0, 0, 0])
                if typ == "point":
                    scene[name] = {"type": "point", "position": vec(keys, "O"), "intensity": rgb(color)}
                elif typ in ("square", "area"):
                    o, dx, dy = vec(keys, "O"), vec(keys, "Dx"), vec(keys, "Dy")
                    n = normalize(cross(dx, dy))
                    eps = 1e-4 * max(math.sqrt(dot(dx, dx)), math.sqrt(dot(dy, dy)))
                    for side, flip in (("front", False), ("back", True)):
                        offset = scale(n, -eps if flip else eps)
                        scene[f"{name}_{side}"] = {
                            "type": "rectangle", "to_world": affine(mi, dx, dy, n, add(o, offset)),
                            "flip_normals": flip, "bsdf": BLACK,
                            "emitter": {"type": "area", "radiance": rgb(color)},
                        }
                elif typ == "sphere":
                    scene[name] = {"type": "sphere", "center": vec(keys, "O"), "radius": num(keys, "R"),
                                   "bsdf": BLACK, "emitter": {"type": "area", "radiance": rgb(color)}}
                else:
                    raise SceneError(f"unknown light type `{typ}`")
                continue
            if kind != "primitive":
                continue
            bsdf, medium = material(keys, state)
            shapes = []
            if typ == "sphere":
                radius = num(keys, "R")
                if radius >= HUGE_RADIUS:
                    raise SceneError(f"a sphere of radius {radius} is beyond Mitsuba's single precision")
                shapes.append({"type": "sphere", "center": vec(keys, "O"), "radius": radius})
            elif typ == "square":
                o, dx, dy = vec(keys, "O"), vec(keys, "Dx"), vec(keys, "Dy")
                shapes.append({"type": "rectangle", "to_world": affine(mi, dx, dy, normalize(cross(dx, dy)), o)})
            elif typ == "plane":
                n = normalize(vec(keys, "N"))
                centre = sub(eye, scale(n, dot(eye, n) - num(keys, "R")))
                t, b = basis(n)
                shapes.append({"type": "rectangle", "to_world": affine(
                    mi, scale(t, PLANE_HALF_SIZE), scale(b, PLANE_HALF_SIZE), n, centre)})
            elif typ == "cylinder":
                p0, p1, radius = vec(keys, "O1"), vec(keys, "O2"), num(keys, "R")
                axis = normalize(sub(p1, p0))
                shapes.append({"type": "cylinder", "p0": p0, "p1": p1, "radius": radius})
                for centre, n in ((p0, scale(axis, -1.0)), (p1, axis)):
                    t, b = basis(n)
                    shapes.append({"type": "disk", "to_world": affine(mi, scale(t, radius), scale(b, radius), n, centre)})
            else:
                raise SceneError(f"primitive `{typ}` is not converted")
            for part, shape in enumerate(shapes):
                shape["bsdf"] = bsdf
                if medium is not None:
                    shape["interior"] = medium
                scene[f"{name}_{part}"] = shape
        except SceneError as e:
            raise SceneError(f"{path}: block {index + 1} (`{kind} {typ or ''}`): {e}") from None

    if "top" in background or "bottom" in background:
        import numpy as np
        top = vec(background, "top", [1, 1, 1])
        bottom = vec(background, "bottom", [1, 1, 1])
        rows = np.zeros((GRADIENT_ROWS, 8, 3), dtype=np.float32)
        for i in range(GRADIENT_ROWS):
            z = math.cos((i + 0.5) / GRADIENT_ROWS * math.pi)
            t = 0.5 * (z + 1.0)
            rows[i, :, :] = [bottom[c] * (1 - t) + top[c] * t for c in range(3)]
        scene["environment"] = {"type": "envmap", "bitmap": mi.Bitmap(rows),
                                "to_world": mi.ScalarTransform4f().rotate(axis=[1, 0, 0], angle=90)}
    else:
        color = vec(background, "color", [0, 0, 0])
        if any(c > 0 for c in color):
            scene["environment"] = {"type": "constant", "radiance": rgb(color)}

    fov = math.degrees(2.0 * math.atan(lens_w / 2.0))
    film = {"type": "hdrfilm", "width": width, "height": height, "rfilter": {"type": "box"},
            "pixel_format": "rgb", "component_format": "float32"}
    sampler = {"type": "independent", "sample_count": spp, "seed": seed}
    to_world = mi.ScalarTransform4f().look_at(origin=eye, target=add(eye, forward), up=up)
    sensor = {"type": "perspective", "fov": fov, "fov_axis": "x", "to_world": to_world,
              "film": film, "sampler": sampler}
    aperture = num(cam, "aperture", 0.0)
    if aperture > 0:
        focus = num(cam, "focal_dist", 0.0)
        if focus <= 0:
            probe = mi.load_dict({**scene, "sensor": sensor})
            hit = probe.ray_intersect(mi.Ray3f(o=eye, d=forward))
            valid = hit.is_valid() if isinstance(hit.is_valid(), bool) else bool(hit.is_valid()[0])
            focus = (float(hit.t) if isinstance(hit.t, float) else float(hit.t[0])) if valid else 1.0
        sensor.update({"type": "thinlens", "aperture_radius": aperture, "focus_distance": focus})
    scene["sensor"] = sensor
    scene["integrator"] = {"type": "volpath" if state["media"] else "path", "max_depth": max_depth,
                           "rr_depth": 5}
    return scene


def parse_size(text):
    w, _, h = text.lower().partition("x")
    return int(w), int(h)


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("scene")
    parser.add_argument("-o", "--output", required=True, help="output image (.exr: linear float)")
    parser.add_argument("--size", type=parse_size, help="WxH, instead of the scene's image_W, image_H")
    parser.add_argument("--spp", type=int, default=64)
    parser.add_argument("--max-depth", type=int, default=10)
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--threads", type=int, default=0, help="worker threads [default: one per core]")
    parser.add_argument("--variant", default="scalar_rgb", choices=["scalar_rgb", "llvm_ad_rgb"],
                        help="Mitsuba's variant [default: scalar_rgb]")
    args = parser.parse_args()

    import drjit as dr
    import mitsuba as mi
    mi.set_variant(args.variant)
    if args.threads > 0:
        dr.set_thread_count(args.threads)
    width, height = args.size or (None, None)
    started = time.perf_counter()
    try:
        scene_dict = convert(mi, args.scene, width, height, args.spp, args.max_depth, args.seed)
    except SceneError as e:
        print(f"error: {e}", file=sys.stderr)
        return 2
    scene = mi.load_dict(scene_dict)
    loaded = time.perf_counter()
    image = mi.render(scene, spp=args.spp, seed=args.seed)
    dr.eval(image)
    dr.sync_thread()
    rendered = time.perf_counter()
    mi.Bitmap(image).write(args.output)
    film = scene.sensors()[0].film().size()
    samples = int(film[0]) * int(film[1]) * args.spp
    print(f"mitsuba: render {rendered - loaded:.3f} s, load {loaded - started:.3f} s, {samples} samples")
    return 0


if __name__ == "__main__":
    sys.exit(main())
