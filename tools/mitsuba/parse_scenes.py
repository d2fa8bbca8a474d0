#!/usr/bin/env python3
"""Print what Mitsuba 3's own scene parser reads from scene files, for rayterra's reader to be
compared with (crates/raytracer/tests/mitsuba_xml.rs).

Usage: parse_scenes.py FILE[::name=value,...] ...

For each file, `mitsuba.parser.parse_file` (variant `scalar_rgb`, the given definitions) and one
line a fact, tab-separated:

    FILE    <path>
    ERROR   <first line of Mitsuba's message>          (when the file does not parse)
    COUNT   <object type>   <number of plugins of that type>
    MATRIX  <name>          <16 numbers, row by row>   (each to_world / to_uv, in node order)

Nodes are in Mitsuba's order: the order of the file, includes in place (a preorder).
"""

import sys

import mitsuba as mi

mi.set_variant("scalar_rgb")
# Warnings go to standard output, where the results are.
mi.set_log_level(mi.LogLevel.Error)
config = mi.parser.ParserConfig("scalar_rgb")

for arg in sys.argv[1:]:
    path, _, defines = arg.partition("::")
    params = dict(d.split("=", 1) for d in defines.split(",") if d)
    print(f"FILE\t{path}")
    try:
        state = mi.parser.parse_file(config, path, **params)
    except Exception as e:  # noqa: BLE001 - any failure is reported as data
        print(f"ERROR\t{str(e).splitlines()[0] if str(e) else type(e).__name__}")
        continue
    counts = {}
    matrices = []
    for node in state.nodes:
        kind = str(node.type).split(".")[-1]
        counts[kind] = counts.get(kind, 0) + 1
        for key in node.props.keys():
            if key in ("to_world", "to_uv"):
                m = node.props[key].matrix
                matrices.append((key, [float(m[i][j]) for i in range(4) for j in range(4)]))
    for kind in sorted(counts):
        print(f"COUNT\t{kind}\t{counts[kind]}")
    for key, values in matrices:
        print(f"MATRIX\t{key}\t" + " ".join(repr(v) for v in values))
