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
turns: each of --rounds rounds casts each set --runs times at Embree, then --runs times at
rayterra (in one process, so both cast with warm caches); the best cast of each counts, so a
busy moment of the machine slows both sides alike or neither.
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


def embree_cast(scene, o, d, runs):
    """Casts the rays `runs` times at Embree: (hit distances, best CPU seconds)."""
    best, dist = float("inf"), None
    for _ in range(runs):
        start = time.thread_time()
        dist = scene.run(o, d, query="DISTANCE")
        best = min(best, time.thread_time() - start)
    return np.asarray(dist, dtype=np.float32), best


def write_rays(o, d, tmp):
    """Writes the rays for the benchmark binary (little-endian f32: origin, direction); returns
    the file's path."""
    rays = os.path.join(tmp, "rays.bin")
    np.concatenate([o, d], axis=1).astype("<f4").tofile(rays)
    return rays


def rayterra_cast(binary, mesh, rays, runs, tmp):
    """Casts the rays of the file `rays` `runs` times at rayterra's BVH: (hit distances, best CPU
    seconds)."""
    out = os.path.join(tmp, "hits.bin")
    text = subprocess.run([binary, "--mesh", mesh, "--rays", rays, "--out", out, "--runs", str(runs)],
                          check=True, capture_output=True, text=True).stdout
    return np.fromfile(out, dtype="<f4"), float(re.search(r"seconds ([0-9.eE+-]+)", text).group(1))


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
    parser.add_argument("--runs", type=int, default=3, help="casts of each set per side and round")
    parser.add_argument("--rounds", type=int, default=3, help="rounds of turns; the best cast counts")
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
          f"best of {args.rounds} x {args.runs} casts each, taking turns")
    print(f"{'rays':<12}{'Embree':>14}{'rayterra':>14}{'rayterra/Embree':>18}   agreement")
    with tempfile.TemporaryDirectory() as tmp:
        for name, (o, d) in [("primary", primary_rays(lo, hi, n)), ("incoherent", incoherent_rays(lo, hi, args.rays))]:
            rays = write_rays(o, d, tmp)
            te = tr = float("inf")
            for _ in range(args.rounds):
                e, t = embree_cast(scene, o, d, args.runs)
                te = min(te, t)
                r, t = rayterra_cast(binary, args.mesh, rays, args.runs, tmp)
                tr = min(tr, t)
            e = np.where(e >= 1e30, np.inf, e)
            both = np.isfinite(e) & np.isfinite(r)
            differ = np.isfinite(e) != np.isfinite(r)
            close = np.abs(e[both] - r[both]) <= 1e-4 * np.maximum(1, np.abs(e[both]))
            rate_e, rate_r = len(o) / te / 1e6, len(o) / tr / 1e6
            print(f"{name:<12}{rate_e:>9.2f} M/s{rate_r:>9.2f} M/s{rate_r / rate_e:>18.2f}   "
                  f"{both.sum()} hit by both ({close.mean() * 100:.3f}% at the same distance), "
                  f"{differ.sum()} hit by one only")


if __name__ == "__main__":
    main()
