#!/usr/bin/env python3
"""Render a Mitsuba 3 scene file with Mitsuba 3 itself: the reference rayterra's reading of the
same file is compared with (`crates/raytracer/tests/mitsuba_scenes.rs`, the `pbr` bench).

Usage:
    python tools/mitsuba/render_xml.py SCENE.xml -o OUT.exr [-D name=value ...] [--spp N]
        [--size WxH] [--seed N] [--variant scalar_rgb|llvm_ad_rgb]

`-D` is Mitsuba's own (`$name` in the file); `--spp` overrides the sampler's count for this render;
`--size` renders the first sensor's view at another size (the same horizontal field of view,
to_world and reconstruction filter, a new film), as rayterra's `--size` does.
The output is Mitsuba's linear RGB film (EXR). It prints one line:
`mitsuba: render <seconds> s, load <seconds> s, <samples> samples`.
`--variant llvm_ad_rgb` needs LLVM (see docs/raytracer-speed.md).
"""
import argparse
import sys
import time


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("scene")
    ap.add_argument("-o", "--output", required=True)
    ap.add_argument("-D", dest="defines", action="append", default=[])
    ap.add_argument("--spp", type=int)
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--size")
    ap.add_argument("--variant", default="scalar_rgb")
    a = ap.parse_args()

    import mitsuba as mi

    mi.set_variant(a.variant)
    params = {}
    for d in a.defines:
        if "=" not in d:
            sys.exit(f"-D {d}: expected name=value")
        k, v = d.split("=", 1)
        params[k] = v
    t0 = time.perf_counter()
    scene = mi.load_file(a.scene, **params)
    load = time.perf_counter() - t0
    sensor = scene.sensors()[0]
    if a.size:
        w, h = (int(x) for x in a.size.lower().split("x"))
        params = mi.traverse(sensor)
        film = {"type": "hdrfilm", "width": w, "height": h, "rfilter": sensor.film().rfilter()}
        sampler = {"type": "independent", "sample_count": sensor.sampler().sample_count()}
        if "x_fov" in params:
            fov = params["x_fov"]
            fov = float(fov[0] if hasattr(fov, "__len__") else fov)
            view = {"type": "perspective", "fov": fov, "fov_axis": "x"}
        elif sensor.class_name() == "OrthographicCamera":
            # The visible width is to_world's; the height follows the new film's aspect.
            near = params["near_clip"]
            view = {"type": "orthographic", "near_clip": float(near[0] if hasattr(near, "__len__") else near)}
        else:
            sys.exit(f"--size: cannot resize the sensor {sensor.class_name()}")
        view.update({"to_world": sensor.world_transform(), "film": film, "sampler": sampler})
        sensor = mi.load_dict(view)
    t1 = time.perf_counter()
    image = mi.render(scene, sensor=sensor, seed=a.seed, spp=a.spp or 0)
    if not a.variant.startswith("scalar"):
        import drjit as dr

        dr.eval(image)
        dr.sync_thread()
    render = time.perf_counter() - t1
    # An `aov` integrator's film holds its AOVs after the colour: keep the colour.
    import numpy as np

    pixels = np.array(image)
    mi.util.write_bitmap(a.output, pixels[..., :3] if pixels.ndim == 3 and pixels.shape[2] > 3 else pixels)
    spp = a.spp or sensor.sampler().sample_count()
    size = sensor.film().crop_size()
    print(f"mitsuba: render {render:.3f} s, load {load:.3f} s, {spp * size[0] * size[1]} samples")


if __name__ == "__main__":
    main()
