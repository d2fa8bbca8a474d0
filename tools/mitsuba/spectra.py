#!/usr/bin/env python3
"""Print the RGB that Mitsuba 3's RGB variant (`scalar_rgb`) gives spectrum files, for rayterra's
reduction of spectra to be compared with (crates/raytracer/tests/mitsuba_xml.rs).

Usage: spectra.py FILE.spd ...

For each file, three tab-separated lines `USE  <file>  r g b`, the file given as
- `bounded`: a diffuse BSDF's `reflectance`,
- `unbounded`: a conductor's `eta`,
- `emission`: an area emitter's `radiance`,
each read back from the loaded plugin with `mitsuba.traverse`.
"""

import sys

import mitsuba as mi

mi.set_variant("scalar_rgb")
# The warnings about clamped colours go to standard output, where the results are.
mi.set_log_level(mi.LogLevel.Error)

SCENES = {
    "bounded": ('<bsdf version="3.0.0" type="diffuse"><spectrum name="reflectance" filename="{f}"/></bsdf>',
                "reflectance.value"),
    "unbounded": ('<bsdf version="3.0.0" type="conductor"><spectrum name="eta" filename="{f}"/></bsdf>',
                  "eta.value"),
    "emission": ('<shape version="3.0.0" type="sphere"><emitter type="area">'
                 '<spectrum name="radiance" filename="{f}"/></emitter></shape>',
                 "emitter.radiance.value"),
}

for path in sys.argv[1:]:
    for use, (xml, key) in SCENES.items():
        params = mi.traverse(mi.load_string(xml.format(f=path)))
        value = params[key]
        rgb = [float(value[i]) for i in range(3)]
        print(f"{use}\t{path}\t" + " ".join(repr(v) for v in rgb))
