//! Ray throughput of the triangle-mesh BVH, single-threaded: `cargo bench -p raytracer --bench
//! mesh_rays`.
//!
//! Without arguments it loads the course's Stanford bunny (`../shared/course-assets/meshes/
//! bunny.obj`), casts 1,000,000 primary rays (a 1000 x 1000 camera on the bunny) and 1,000,000
//! incoherent rays (random origins around the bunny aimed at random points of its box) and prints
//! the rays a second. With `--features compare-obvhs` it casts the same rays at the `obvhs`
//! crate's CWBVH built over the same triangles and prints the ratio.
//!
//! `tools/embree/bench.py` drives it to compare with Embree on exactly the same rays:
//! `-- --mesh FILE --rays FILE --out FILE` reads rays (little-endian f32: origin x y z, direction
//! x y z, per ray), then casts them once for every line it reads on its standard input, printing
//! `seconds S` (the casting thread's CPU time) after each, so that the script can alternate
//! single casts of Embree and of rayterra; at the end of its input it writes the hit distance of
//! each ray (f32, infinity for a miss) to the `--out` file.

use std::io::Write;
use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::time::Instant;

use raytracer::geometry::MeshRay;
use raytracer::geometry::obj::{MeshTransform, load_obj};
use raytracer::geometry::{TriangleIndices, TriangleMesh};

fn main() {
    let args: Vec<String> = std::env::args().skip(1).filter(|a| a != "--bench").collect();
    let value =
        |name: &str| args.iter().position(|a| a == name).and_then(|i| args.get(i + 1)).map(PathBuf::from);
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("../..");
    let mesh_path = value("--mesh").unwrap_or_else(|| root.join("../shared/course-assets/meshes/bunny.obj"));
    if !mesh_path.is_file() {
        eprintln!("**** the mesh {} is missing: nothing to measure ****", mesh_path.display());
        return;
    }
    let started = Instant::now();
    let obj = load_obj(&mesh_path, &MeshTransform::default()).expect("a readable mesh");
    let loaded = started.elapsed().as_secs_f64();
    let tris: Vec<TriangleIndices> = obj.groups.iter().flat_map(|g| g.1.iter().copied()).collect();
    let started = Instant::now();
    let mesh = TriangleMesh::new(Arc::clone(&obj.vertices), &tris);
    mesh.build_bvh();
    let built = started.elapsed().as_secs_f64();

    if let (Some(rays), Some(out)) = (value("--rays"), value("--out")) {
        let rays = read_rays(&rays);
        let mut hits = vec![f32::INFINITY; rays.len()];
        let mut stdout = std::io::stdout().lock();
        for line in std::io::stdin().lines() {
            line.expect("read a request");
            let (h, seconds) = cast(&mesh, &rays);
            hits = h;
            writeln!(stdout, "seconds {seconds:.9}").and_then(|()| stdout.flush()).expect("write the time");
        }
        let bytes: Vec<u8> = hits.iter().flat_map(|t| t.to_le_bytes()).collect();
        std::fs::write(&out, bytes).expect("write the hit distances");
        return;
    }

    println!(
        "mesh {}: {} triangles, read in {loaded:.3} s, BVH built in {built:.3} s, {:.0} bytes a triangle",
        mesh_path.display(),
        mesh.len(),
        (mesh.memory() + obj.vertices.positions.len() * 12 + obj.vertices.normals.len() * 12) as f64
            / mesh.len() as f64
    );
    let b = mesh.bounds();
    let (lo, hi) =
        ([b.min.x as f32, b.min.y as f32, b.min.z as f32], [b.max.x as f32, b.max.y as f32, b.max.z as f32]);
    for (name, rays) in
        [("primary", primary_rays(lo, hi, 1000)), ("incoherent", incoherent_rays(lo, hi, 1_000_000))]
    {
        let mut best = f64::INFINITY;
        let mut hit_count = 0;
        for _ in 0..3 {
            let (hits, seconds) = cast(&mesh, &rays);
            best = best.min(seconds);
            hit_count = hits.iter().filter(|t| t.is_finite()).count();
        }
        println!(
            "{name:>10}: {} rays ({hit_count} hit) in {best:.3} s: {:.2} M rays/s (one thread, CPU time, best of 3)",
            rays.len(),
            rays.len() as f64 / best / 1e6
        );
        #[cfg(feature = "compare-obvhs")]
        obvhs_compare::run(&mesh, &rays, best);
    }
}

/// A ray as six f32: origin, direction.
type RawRay = [f32; 6];

/// Casts every ray (closest hit) on one thread; returns the distances and the time.
fn cast(mesh: &TriangleMesh, rays: &[RawRay]) -> (Vec<f32>, f64) {
    let mut hits = vec![f32::INFINITY; rays.len()];
    let clock = ThreadClock::start();
    for (r, out) in rays.iter().zip(hits.iter_mut()) {
        let ray = MeshRay::from_f32([r[0], r[1], r[2]], [r[3], r[4], r[5]]);
        if let Some((_, t, _, _)) = mesh.intersect_f32(&ray, f32::INFINITY) {
            *out = t;
        }
    }
    (hits, clock.seconds())
}

/// The CPU time of this thread (`CLOCK_THREAD_CPUTIME_ID`, to the nanosecond), which other
/// processes on a shared machine disturb far less than the wall clock. (Not
/// `/proc/thread-self/schedstat`: on this machine it advances only at scheduler ticks, 4 ms
/// apart, a sixteenth of a million primary rays' time.)
struct ThreadClock {
    start: std::time::Duration,
}

impl ThreadClock {
    fn start() -> ThreadClock {
        ThreadClock { start: thread_cpu_time() }
    }

    fn seconds(&self) -> f64 {
        (thread_cpu_time() - self.start).as_secs_f64()
    }
}

fn thread_cpu_time() -> std::time::Duration {
    let t = rustix::time::clock_gettime(rustix::time::ClockId::ThreadCPUTime);
    std::time::Duration::new(t.tv_sec as u64, t.tv_nsec as u32)
}

fn read_rays(path: &Path) -> Vec<RawRay> {
    let bytes = std::fs::read(path).expect("read the rays");
    bytes
        .chunks_exact(24)
        .map(|c| {
            std::array::from_fn(|i| f32::from_le_bytes([c[4 * i], c[4 * i + 1], c[4 * i + 2], c[4 * i + 3]]))
        })
        .collect()
}

/// `n x n` camera rays through the box's middle, from in front of it (-z side... along +z
/// towards the box from its low-z side, framing the box).
fn primary_rays(lo: [f32; 3], hi: [f32; 3], n: usize) -> Vec<RawRay> {
    let c = [(lo[0] + hi[0]) / 2.0, (lo[1] + hi[1]) / 2.0, (lo[2] + hi[2]) / 2.0];
    let size = (hi[0] - lo[0]).max(hi[1] - lo[1]).max(hi[2] - lo[2]);
    let eye = [c[0], c[1], c[2] + 2.5 * size];
    let mut rays = Vec::with_capacity(n * n);
    for i in 0..n {
        for j in 0..n {
            let x = c[0] + size * 0.6 * ((j as f32 + 0.5) / n as f32 * 2.0 - 1.0);
            let y = c[1] + size * 0.6 * ((i as f32 + 0.5) / n as f32 * 2.0 - 1.0);
            let d = [x - eye[0], y - eye[1], c[2] - eye[2]];
            let l = (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt();
            rays.push([eye[0], eye[1], eye[2], d[0] / l, d[1] / l, d[2] / l]);
        }
    }
    rays
}

/// Rays from random points of a sphere around the box to random points inside it.
fn incoherent_rays(lo: [f32; 3], hi: [f32; 3], n: usize) -> Vec<RawRay> {
    let mut state = 0x9E37_79B9_7F4A_7C15u64;
    let mut uniform = move || {
        state ^= state << 13;
        state ^= state >> 7;
        state ^= state << 17;
        (state >> 40) as f32 / (1u64 << 24) as f32
    };
    let c = [(lo[0] + hi[0]) / 2.0, (lo[1] + hi[1]) / 2.0, (lo[2] + hi[2]) / 2.0];
    let size = (hi[0] - lo[0]).max(hi[1] - lo[1]).max(hi[2] - lo[2]);
    (0..n)
        .map(|_| {
            let z = 2.0 * uniform() - 1.0;
            let phi = std::f32::consts::TAU * uniform();
            let r = (1.0 - z * z).max(0.0).sqrt();
            let o = [c[0] + size * r * phi.cos(), c[1] + size * r * phi.sin(), c[2] + size * z];
            let t = [
                lo[0] + (hi[0] - lo[0]) * uniform(),
                lo[1] + (hi[1] - lo[1]) * uniform(),
                lo[2] + (hi[2] - lo[2]) * uniform(),
            ];
            let d = [t[0] - o[0], t[1] - o[1], t[2] - o[2]];
            let l = (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt();
            [o[0], o[1], o[2], d[0] / l, d[1] / l, d[2] / l]
        })
        .collect()
}

#[cfg(feature = "compare-obvhs")]
mod obvhs_compare {
    //! The same rays at the `obvhs` crate's compressed wide BVH (CWBVH, built with its default
    //! "medium" preset: PLOC, reinsertion, spatial pre-splits), with its own triangle test.
    use std::time::{Duration, Instant};

    use glam::Vec3A;
    use obvhs::BvhBuildParams;
    use obvhs::cwbvh::builder::build_cwbvh_from_tris;
    use obvhs::ray::{Ray, RayHit};
    use obvhs::triangle::Triangle;
    use raytracer::geometry::TriangleMesh;

    use super::{RawRay, ThreadClock};

    pub fn run(mesh: &TriangleMesh, rays: &[RawRay], ours: f64) {
        let tris: Vec<Triangle> = (0..mesh.len() as u32)
            .map(|i| {
                let c = mesh.corners(i);
                Triangle { v0: c[0].as_vec3a(), v1: c[1].as_vec3a(), v2: c[2].as_vec3a() }
            })
            .collect();
        let started = Instant::now();
        let bvh = build_cwbvh_from_tris(&tris, BvhBuildParams::medium_build(), &mut Duration::default());
        let built = started.elapsed().as_secs_f64();
        let mut best = f64::INFINITY;
        let mut agree = 0usize;
        for _ in 0..3 {
            let clock = ThreadClock::start();
            let mut hits = 0usize;
            for r in rays {
                let ray = Ray::new_inf(Vec3A::new(r[0], r[1], r[2]), Vec3A::new(r[3], r[4], r[5]));
                let mut hit = RayHit::none();
                if bvh.ray_traverse(ray, &mut hit, |ray, id| {
                    tris[bvh.primitive_indices[id] as usize].intersect(ray)
                }) {
                    hits += 1;
                }
            }
            best = best.min(clock.seconds());
            agree = hits;
        }
        println!(
            "{:>10}  obvhs CWBVH (built in {built:.3} s): {:.2} M rays/s ({agree} hit); ours / obvhs = {:.2}",
            "",
            rays.len() as f64 / best / 1e6,
            best / ours
        );
    }
}
