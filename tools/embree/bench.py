#!/usr/bin/env python3
"""Ray throughput of rayterra's mesh BVH against Embree, on exactly the same rays.

Loads the Stanford bunny (../shared/course-assets/meshes/bunny.obj by default), makes 1,000,000
primary rays (a 1000 x 1000 camera framing the bunny from the front) and 1,000,000 incoherent
rays (from random points of a sphere around it to random points of its box), and casts each set,
single-threaded and closest hit, at Embree (through `embreex`) and at rayterra's BVH (the
`mesh_rays` benchmark binary, which reads the same rays from a file). Prints both rates, their
ratio, and how well the hit distances agree. Run it from the repository root:

    python3 -m venv target/embree-venv
    target/embree-venv/bin/pip install -r tools/embree/requirements.txt
    target/embree-venv/bin/python tools/embree/bench.py

Both sides time only the casting (not loading or building), as the CPU time of the casting
thread (which other work on a shared machine disturbs far less than the wall clock). They take
turns cast by cast: each of --rounds rounds casts the set once at Embree, then once at rayterra
(whose process stays up between rounds, so both cast with warm caches), after one cast of each
to warm up. The speed of this shared machine drifts by tens of percent over seconds, so the
script prints the best cast of each side and the median and range of the rounds' ratios (each
round's two casts run within a fraction of a second of each other).
"""

import argparse
import os
import re
import subprocess
import sys
import tempfile
import time

import numpy as np
import trimesh
from embreex import rtcore_scene
from embreex.mesh_construction import TriangleMesh

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))


def primary_rays(lo, hi, n):
    """n x n rays from a camera in front of the box (on its +z side), framing it."""
    centre = (lo + hi) / 2
    size = float((hi - lo).max())
    eye = np.array([centre[0], centre[1], centre[2] + 2.5 * size], dtype=np.float64)
    s = (np.arange(n) + 0.5) / n * 2 - 1
    x, y = np.meshgrid(centre[0] + 0.6 * size * s, centre[1] + 0.6 * size * s)
    d = np.stack([x - eye[0], y - eye[1], np.full_like(x, centre[2] - eye[2])], axis=-1).reshape(-1, 3)
    d /= np.linalg.norm(d, axis=1, keepdims=True)
    o = np.broadcast_to(eye, d.shape)
    return o.astype(np.float32), d.astype(np.float32)


def incoherent_rays(lo, hi, n, seed=1):
    """Rays from random points of a sphere around the box to random points inside it."""
    rng = np.random.default_rng(seed)
    centre = (lo + hi) / 2
    size = float((hi - lo).max())
    v = rng.normal(size=(n, 3))
    o = centre + size * v / np.linalg.norm(v, axis=1, keepdims=True)
    t = lo + (hi - lo) * rng.random((n, 3))
    d = t - o
    d /= np.linalg.norm(d, axis=1, keepdims=True)
    return o.astype(np.float32), d.astype(np.float32)


def embree_cast(scene, o, d):
    """Casts the rays once at Embree: (hit distances, CPU seconds)."""
    start = time.thread_time()
    dist = scene.run(o, d, query="DISTANCE")
    return np.asarray(dist, dtype=np.float32), time.thread_time() - start


def write_rays(o, d, tmp):
    """Writes the rays for the benchmark binary (little-endian f32: origin, direction); returns
    the file's path."""
    rays = os.path.join(tmp, "rays.bin")
    np.concatenate([o, d], axis=1).astype("<f4").tofile(rays)
    return rays


class Rayterra:
    """The mesh_rays benchmark binary holding the mesh and the rays of the file `rays`; casts them
    once per request."""

    def __init__(self, binary, mesh, rays, tmp):
        self.out = os.path.join(tmp, "hits.bin")
        self.process = subprocess.Popen([binary, "--mesh", mesh, "--rays", rays, "--out", self.out],
                                        stdin=subprocess.PIPE, stdout=subprocess.PIPE, text=True)

    def cast(self):
        """Casts the rays once: the CPU seconds."""
        self.process.stdin.write("cast\n")
        self.process.stdin.flush()
        line = self.process.stdout.readline()
        m = re.match(r"seconds ([0-9.eE+-]+)", line)
        if not m:
            sys.exit(f"unexpected answer from the benchmark binary: {line!r}")
        return float(m.group(1))

    def finish(self):
        """Ends the process; the hit distances of the last cast."""
        self.process.stdin.close()
        if self.process.wait() != 0:
            sys.exit("the benchmark binary failed")
        return np.fromfile(self.out, dtype="<f4")


def bench_binary():
    """Builds the mesh_rays benchmark in release mode and returns its path."""
    text = subprocess.run(
        ["cargo", "bench", "-p", "raytracer", "--bench", "mesh_rays", "--no-run", "--message-format=json"],
        cwd=ROOT, check=True, capture_output=True, text=True).stdout
    for line in text.splitlines():
        m = re.search(r'"executable":"([^"]+mesh_rays[^"]*)"', line)
        if m:
            return m.group(1)
    sys.exit("cannot find the mesh_rays benchmark binary")


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--mesh", default=os.path.join(ROOT, "../shared/course-assets/meshes/bunny.obj"))
    parser.add_argument("--rays", type=int, default=1_000_000, help="rays per set (default 1,000,000)")
    parser.add_argument("--rounds", type=int, default=15,
                        help="rounds of turns, one cast of each side a round (default 15)")
    args = parser.parse_args()
    if not os.path.isfile(args.mesh):
        sys.exit(f"the mesh {args.mesh} is missing (the course assets belong in ../shared beside the repository)")

    binary = bench_binary()
    mesh = trimesh.load(args.mesh, process=False, force="mesh")
    vertices = np.asarray(mesh.vertices, dtype=np.float32)
    faces = np.asarray(mesh.faces, dtype=np.int32)
    scene = rtcore_scene.EmbreeScene()
    TriangleMesh(scene, vertices[faces])
    lo, hi = vertices.min(axis=0).astype(np.float64), vertices.max(axis=0).astype(np.float64)
    n = int(round(args.rays ** 0.5))
    print(f"{args.mesh}: {len(faces)} triangles; one thread, closest hit, "
          f"{args.rounds} rounds of one cast each, taking turns")
    print(f"{'rays':<12}{'Embree':>12}{'rayterra':>12}   rayterra/Embree: median (range)   agreement")
    with tempfile.TemporaryDirectory() as tmp:
        for name, (o, d) in [("primary", primary_rays(lo, hi, n)), ("incoherent", incoherent_rays(lo, hi, args.rays))]:
            rayterra = Rayterra(binary, args.mesh, write_rays(o, d, tmp), tmp)
            embree_cast(scene, o, d)
            rayterra.cast()
            te, tr, ratios = [], [], []
            for _ in range(args.rounds):
                e, t_e = embree_cast(scene, o, d)
                t_r = rayterra.cast()
                te.append(t_e)
                tr.append(t_r)
                ratios.append(t_e / t_r)
            r = rayterra.finish()
            e = np.where(e >= 1e30, np.inf, e)
            both = np.isfinite(e) & np.isfinite(r)
            differ = np.isfinite(e) != np.isfinite(r)
            close = np.abs(e[both] - r[both]) <= 1e-4 * np.maximum(1, np.abs(e[both]))
            rate_e, rate_r = len(o) / min(te) / 1e6, len(o) / min(tr) / 1e6
            print(f"{name:<12}{rate_e:>6.2f} M/s{rate_r:>8.2f} M/s   "
                  f"{np.median(ratios):>6.2f} ({min(ratios):.2f}-{max(ratios):.2f})"
                  f"{'':>17}{both.sum()} hit by both ({close.mean() * 100:.3f}% at the same distance), "
                  f"{differ.sum()} hit by one only")

if __name__ == "__main__":
    main()
