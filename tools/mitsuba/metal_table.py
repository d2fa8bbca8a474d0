"""Prints the RGB complex indices of refraction Mitsuba 3's RGB variants give each named
conductor (`<bsdf type="conductor"><string name="material" value="Au"/>`), as the Rust table
`METALS` in crates/raytracer/src/scene/mitsuba/build/ior.rs holds them.

Mitsuba reduces its tabulated spectra (`data/ior/NAME.eta.spd`, `NAME.k.spd`) to RGB when it
loads the material; this asks Mitsuba itself for the result, so the table is Mitsuba's own
reading. Run with the test environment's Python (see docs/mitsuba-format.md):

    target/mitsuba-venv/bin/python tools/mitsuba/metal_table.py NAME...
"""
import sys

import mitsuba as mi

mi.set_variant("scalar_rgb")
mi.set_log_level(mi.LogLevel.Error)
for name in sys.argv[1:]:
    params = mi.traverse(mi.load_dict({"type": "conductor", "material": name}))
    eta, k = params["eta.value"], params["k.value"]
    print(f'    ("{name}", [{eta[0]:.6}, {eta[1]:.6}, {eta[2]:.6}], [{k[0]:.6}, {k[1]:.6}, {k[2]:.6}]),')
