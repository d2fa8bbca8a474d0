//! The physically based emitters (Mitsuba's) as the path tracer samples them: what each emits,
//! next-event estimation (an emitter chosen in proportion to an estimate of its power, then a
//! point or direction on it) and the densities multiple importance sampling needs.
//!
//! - `area` on a triangle mesh: a triangle chosen by area, a point uniform on it; radiance leaves
//!   the front face only (the side of `(p1 - p0) x (p2 - p0)`);
//! - `area` on a sphere: a direction uniform in the cone the sphere fills (outside it), radiance
//!   leaving outwards;
//! - `point`, `spot` (Mitsuba's fall-off, linear in angle between `beam_width` and
//!   `cutoff_angle`), `projector` (an image projected from a point, Mitsuba's normalisation) and
//!   `directional`: delta lights;
//! - `constant` and `envmap`: the environment, the map sampled texel by texel in proportion to
//!   luminance times `sin theta` (the texel's solid angle), then uniformly inside the texel.
//!
//! Densities are per unit solid angle at the receiving point, the emitter's choice included.

use std::f64::consts::{PI, TAU};
use std::sync::Arc;

use glam::DVec3;

use crate::base::color::channel_mean;

use crate::base::sampling::{Discrete, sphere_cone, sphere_cone_pdf};
use crate::geometry::{Bounds, MESH_ERROR_SCALE, Ray, SPAWN_OFFSET, Shape, ShapePart, TriangleMesh};
use crate::light::Emitter;
use crate::material::{Param, TextureSpec};
use crate::prepare::{EnvironmentMap, Interaction, PreparedScene, luminance};

/// What next-event estimation drew: a direction to an emitter and what arrives along it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct EmitterSample {
    /// Unit direction from the receiving point towards the emitter.
    pub wi: DVec3,
    /// The point on the emitter (for the shadow ray); far away for the environment and a
    /// directional emitter.
    pub target: DVec3,
    /// Incident radiance along `wi` (for delta emitters, the irradiance on a surface facing
    /// the light), not divided by the density.
    pub radiance: DVec3,
    /// Density of the direction per steradian, the choice included; for a delta emitter, the
    /// probability of choosing it.
    pub pdf: f64,
    /// Whether the emitter is a delta distribution (BSDF sampling cannot hit it).
    pub delta: bool,
    /// How far short of `target` the shadow ray stops: the rounding error of the emitter's
    /// surface there (0 for points and far targets).
    pub margin: f64,
}

/// How an area emitter's shape is sampled.
#[derive(Debug)]
enum AreaShape {
    /// A mesh: triangles by area.
    Mesh { mesh: Arc<TriangleMesh>, triangles: Discrete, area: f64 },
    /// A sphere: the cone of directions it fills.
    Sphere { centre: DVec3, radius: f64 },
}

/// A projector's image plane: the tangent of half its horizontal field of view and the image's
/// aspect (width over height).
#[derive(Clone, Copy, Debug)]
struct Projection {
    tan_x: f64,
    aspect: f64,
}

/// Points per side of the grid a texture's mean is estimated on (a textured projector's or area
/// light's, for its power).
const TEXTURE_MEAN_GRID: u32 = 16;

/// The environment map's sampling distribution: rows by their weight, then texels in the row.
#[derive(Debug)]
struct MapDistribution {
    rows: Discrete,
    columns: Vec<Discrete>,
}

/// The scene's physically based emitters, ready to sample.
#[derive(Debug)]
pub struct Emitters<'s> {
    scene: &'s PreparedScene,
    /// Emitters by estimated power.
    choose: Discrete,
    /// Per emitter: the shape of an area emitter.
    shapes: Vec<Option<AreaShape>>,
    /// Per emitter: the image plane of a projector.
    projections: Vec<Option<Projection>>,
    /// The environment emitter (`constant` or `envmap`), if any.
    environment: Option<u32>,
    /// The environment map and its distribution.
    map: Option<(Arc<EnvironmentMap>, MapDistribution)>,
    /// Radius of a sphere around the scene (for far points and power estimates).
    radius: f64,
}

impl<'s> Emitters<'s> {
    /// The emitters of `scene`, chosen in proportion to their estimated power.
    pub fn new(scene: &'s PreparedScene) -> Emitters<'s> {
        Emitters::with_choice(scene, false)
    }

    /// The emitters of `scene`, each chosen with the same probability, as Mitsuba 3.9.1 chooses
    /// them (every emitter's `sampling_weight` is 1 by default): the same expectation as
    /// [`Emitters::new`], and Mitsuba's noise (which its `direct` integrator with emitter
    /// samples alone shows plainly, on scenes of lights of very different powers).
    pub fn uniform(scene: &'s PreparedScene) -> Emitters<'s> {
        Emitters::with_choice(scene, true)
    }

    fn with_choice(scene: &'s PreparedScene, uniform: bool) -> Emitters<'s> {
        let s = &scene.scene;
        let mut b = Bounds::EMPTY.include(s.camera.eye);
        for p in &s.primitives {
            if let Some(pb) = p.shape.bounds() {
                b = b.union(pb);
            }
        }
        let radius = ((b.max - b.min).length() * 0.5).max(1e-3);
        let disc = PI * radius * radius;
        let mut environment = None;
        let mut map = None;
        let mut shapes = Vec::with_capacity(s.emitters.len());
        let mut projections = vec![None; s.emitters.len()];
        let mut powers = Vec::with_capacity(s.emitters.len());
        for (i, e) in s.emitters.iter().enumerate() {
            let (shape, power) = match e {
                Emitter::Area { primitive, radiance } => match &s.primitives[*primitive as usize].shape {
                    Shape::Mesh(mesh) => {
                        let areas: Vec<f64> = (0..mesh.len() as u32)
                            .map(|t| {
                                let [p0, p1, p2] = mesh.corners(t);
                                0.5 * (p1 - p0).cross(p2 - p0).length()
                            })
                            .collect();
                        let area: f64 = areas.iter().sum();
                        let shape =
                            AreaShape::Mesh { mesh: mesh.clone(), triangles: Discrete::new(&areas), area };
                        (Some(shape), mean_radiance(scene, radiance) * PI * area)
                    }
                    Shape::Sphere(sp) => (
                        Some(AreaShape::Sphere { centre: sp.centre, radius: sp.radius }),
                        mean_radiance(scene, radiance) * 4.0 * PI * PI * sp.radius * sp.radius,
                    ),
                    _ => (None, 0.0),
                },
                Emitter::Point { intensity, .. } => (None, 4.0 * PI * channel_mean(*intensity)),
                Emitter::Spot { intensity, cos_cutoff, cos_beam, .. } => {
                    (None, TAU * (1.0 - 0.5 * (cos_cutoff + cos_beam)) * channel_mean(*intensity))
                }
                Emitter::Projector { irradiance, scale, tan_half, fov_axis, .. } => {
                    // Mitsuba's `resolution()`: the bitmap's, (1, 1) for anything else.
                    let ((w, h), mean_e) = match irradiance {
                        Param::Constant(c) => ((1, 1), channel_mean(*c)),
                        Param::Texture(t) => (scene.texture_resolution(t), texture_mean(scene, t)),
                    };
                    let aspect = w as f64 / h.max(1) as f64;
                    let tan_x = fov_axis.tan_half_x(*tan_half, aspect);
                    projections[i] = Some(Projection { tan_x, aspect });
                    // The flux through the image plane at distance 1: pi scale E over its area.
                    (None, PI * scale.abs() * mean_e.max(0.0) * 4.0 * tan_x * tan_x / aspect)
                }
                Emitter::Directional { irradiance, .. } => (None, disc * channel_mean(*irradiance)),
                Emitter::Constant { radiance } => {
                    environment = Some(i as u32);
                    (None, disc * 4.0 * PI * channel_mean(*radiance))
                }
                Emitter::Environment { .. } => {
                    environment = Some(i as u32);
                    let power = match scene.environment_map() {
                        Some(m) => {
                            let d = MapDistribution::new(m);
                            let (w, h) = (m.image.width() as f64, m.image.height() as f64);
                            let power = disc * d.rows.total() * m.scale * 2.0 * PI * PI / (w * h);
                            map = Some((m.clone(), d));
                            power
                        }
                        None => 0.0,
                    };
                    (None, power)
                }
            };
            shapes.push(shape);
            powers.push(power);
        }
        if uniform {
            powers.iter_mut().for_each(|p| *p = 1.0);
        }
        Emitters { scene, choose: Discrete::new(&powers), shapes, projections, environment, map, radius }
    }

    /// Whether there is anything to sample.
    pub fn any(&self) -> bool {
        !self.choose.is_empty()
    }

    /// The radiance arriving along a ray of unit direction `dir` that escapes the scene.
    #[inline]
    pub fn environment(&self, dir: DVec3) -> DVec3 {
        match self.environment.map(|i| &self.scene.scene.emitters[i as usize]) {
            Some(Emitter::Constant { radiance }) => *radiance,
            Some(Emitter::Environment { .. }) => {
                self.map.as_ref().map_or(DVec3::ZERO, |(m, _)| m.radiance(dir))
            }
            _ => DVec3::ZERO,
        }
    }

    /// The density with which [`Emitters::sample`] draws the escaping direction `dir`.
    pub fn environment_pdf(&self, dir: DVec3) -> f64 {
        let Some(i) = self.environment else { return 0.0 };
        let p = self.choose.pmf(i as usize);
        match &self.map {
            Some((m, d)) => p * d.pdf(m, dir),
            None => p / (4.0 * PI),
        }
    }

    /// The radiance area emitter `emitter` sends along a ray that meets it at `at` (nothing from
    /// its back face).
    #[inline]
    pub fn emitted(&self, emitter: u32, at: &Interaction) -> DVec3 {
        match &self.scene.scene.emitters[emitter as usize] {
            Emitter::Area { radiance, .. } if at.front => self.scene.param(radiance, at),
            _ => DVec3::ZERO,
        }
    }

    /// The density with which [`Emitters::sample`] at `p` draws the direction `dir` that meets
    /// area emitter `emitter` at distance `t` where its geometric normal is `normal`.
    pub fn area_pdf(&self, emitter: u32, p: DVec3, dir: DVec3, t: f64, normal: DVec3) -> f64 {
        let choice = self.choose.pmf(emitter as usize);
        match self.shapes.get(emitter as usize) {
            Some(Some(AreaShape::Mesh { area, .. })) => {
                let cos = normal.dot(dir).abs();
                if cos <= 1e-12 || *area <= 0.0 { 0.0 } else { choice * t * t / (area * cos) }
            }
            Some(Some(AreaShape::Sphere { centre, radius })) => choice * sphere_cone_pdf(p, *centre, *radius),
            _ => 0.0,
        }
    }

    /// An emitter sample for the point `p`: `u` chooses the emitter, `u1`, `u2` the point or
    /// direction on it. `None` when nothing emits towards `p`.
    pub fn sample(&self, p: DVec3, u: f64, u1: f64, u2: f64) -> Option<EmitterSample> {
        let (index, choice) = self.choose.sample(u)?;
        // Beyond the scene from `p`, for the emitters at infinity (the others need no square root).
        let far = || 2.0 * self.radius + (p - self.scene.scene.camera.eye).length();
        match &self.scene.scene.emitters[index] {
            Emitter::Area { radiance, primitive } => match self.shapes[index].as_ref()? {
                AreaShape::Mesh { mesh, triangles, area } => {
                    let (t, _, u1) = triangles.sample_remapped(u1)?;
                    let s = u1.sqrt();
                    let (b1, b2) = (1.0 - s, u2 * s);
                    let target = mesh.point_at(t as u32, b1 as f32, b2 as f32);
                    let part = ShapePart::Triangle { index: t as u32, b1: b1 as f32, b2: b2 as f32 };
                    let n = mesh.face_normal(t as u32);
                    let to = target - p;
                    let d2 = to.length_squared();
                    let wi = to / d2.sqrt();
                    // One-sided: only the front face emits.
                    let cos = -n.dot(wi);
                    if cos <= 1e-12 || d2 <= 0.0 {
                        return None;
                    }
                    let margin =
                        SPAWN_OFFSET * MESH_ERROR_SCALE * mesh.magnitude().max(target.abs().max_element());
                    Some(EmitterSample {
                        wi,
                        target,
                        radiance: self.scene.param_on(radiance, *primitive, part, target),
                        pdf: choice * d2 / (area * cos),
                        delta: false,
                        margin,
                    })
                }
                AreaShape::Sphere { centre, radius: r } => {
                    let (wi, t, pdf) = sphere_cone(p, *centre, *r, u1, u2)?;
                    Some(EmitterSample {
                        wi,
                        target: p + wi * t,
                        radiance: self.scene.param_on(radiance, *primitive, ShapePart::Main, p + wi * t),
                        pdf: choice * pdf,
                        delta: false,
                        margin: SPAWN_OFFSET
                            * (centre.abs().max_element() + r).max((p + wi * t).abs().max_element()),
                    })
                }
            },
            Emitter::Point { position, intensity } => {
                let to = *position - p;
                let d2 = to.length_squared();
                (d2 > 0.0).then(|| EmitterSample {
                    wi: to / d2.sqrt(),
                    target: *position,
                    radiance: *intensity / d2,
                    pdf: choice,
                    delta: true,
                    margin: 0.0,
                })
            }
            Emitter::Spot { position, axis, intensity, cos_beam, cos_cutoff, texture, to_local } => {
                let to = *position - p;
                let d2 = to.length_squared();
                if d2 <= 0.0 {
                    return None;
                }
                let wi = to / d2.sqrt();
                let cos = -wi.dot(*axis);
                if cos <= *cos_cutoff {
                    return None;
                }
                let falloff = if cos >= *cos_beam {
                    1.0
                } else {
                    let (cutoff, beam) = (cos_cutoff.acos(), cos_beam.acos());
                    ((cutoff - cos.clamp(-1.0, 1.0).acos()) / (cutoff - beam)).clamp(0.0, 1.0)
                };
                let tint = match texture {
                    Some(t) => {
                        // Mitsuba's projection through the cone: the cutoff's edge at 0 and 1.
                        let d = *to_local * -wi;
                        let k = 0.5 / (d.z * (1.0 - cos_cutoff * cos_cutoff).sqrt() / cos_cutoff);
                        self.scene.texture_at(t, 0.5 + k * d.x, 0.5 + k * d.y)
                    }
                    None => DVec3::ONE,
                };
                Some(EmitterSample {
                    wi,
                    target: *position,
                    radiance: *intensity * tint * (falloff / d2),
                    pdf: choice,
                    delta: true,
                    margin: 0.0,
                })
            }
            Emitter::Projector { irradiance, scale, to_world, to_local, .. } => {
                let Projection { tan_x, aspect } = self.projections[index]?;
                // The image coordinates of `p` (Mitsuba's `camera_to_sample`): its local `+x`
                // towards `u = 0`.
                let q = to_local.transform_point3(p);
                if q.z.is_nan() || q.z <= 0.0 {
                    return None;
                }
                let u = 0.5 - 0.5 * q.x / (q.z * tan_x);
                let v = 0.5 - 0.5 * aspect * q.y / (q.z * tan_x);
                if !((0.0..=1.0).contains(&u) && (0.0..=1.0).contains(&v)) {
                    return None;
                }
                let position = to_world.w_axis.truncate();
                let to = position - p;
                let dist = to.length();
                if dist.is_nan() || dist <= 0.0 {
                    return None;
                }
                let wi = to / dist;
                let denominator = q.z * q.z * -to_world.transform_vector3(DVec3::Z).dot(wi);
                if denominator.is_nan() || denominator <= 0.0 {
                    return None;
                }
                let e = match irradiance {
                    Param::Constant(c) => *c,
                    Param::Texture(t) => self.scene.texture_at(t, u, v),
                };
                Some(EmitterSample {
                    wi,
                    target: position,
                    radiance: e * (PI * scale / denominator),
                    pdf: choice,
                    delta: true,
                    margin: 0.0,
                })
            }
            Emitter::Directional { direction, irradiance } => {
                let wi = -*direction;
                Some(EmitterSample {
                    wi,
                    target: p + wi * far(),
                    radiance: *irradiance,
                    pdf: choice,
                    delta: true,
                    margin: 0.0,
                })
            }
            Emitter::Constant { radiance } => {
                let wi = crate::base::sampling::uniform_sphere(u1, u2);
                Some(EmitterSample {
                    wi,
                    target: p + wi * far(),
                    radiance: *radiance,
                    pdf: choice / (4.0 * PI),
                    delta: false,
                    margin: 0.0,
                })
            }
            Emitter::Environment { .. } => {
                let (m, d) = self.map.as_ref()?;
                let (wi, pdf) = d.sample(m, u1, u2)?;
                Some(EmitterSample {
                    wi,
                    target: p + wi * far(),
                    radiance: m.radiance(wi),
                    pdf: choice * pdf,
                    delta: false,
                    margin: 0.0,
                })
            }
        }
    }

    /// Whether nothing blocks the segment from `origin` to the sample's target, stopping the
    /// sample's margin short of it (so that the emitter's own surface does not). Counts the ray
    /// in `rays`.
    pub fn unoccluded(&self, origin: DVec3, sample: &EmitterSample, rays: &mut u64) -> bool {
        *rays += 1;
        let to = sample.target - origin;
        let dist = to.length();
        if dist.is_nan() || dist <= 0.0 {
            return true;
        }
        let t_max = (dist - sample.margin).min(dist * (1.0 - 1e-7));
        !self.scene.occluded(&Ray { origin, dir: to / dist }, t_max)
    }
}

impl MapDistribution {
    /// Texels weighted by luminance times `sin theta` at their centre.
    fn new(map: &EnvironmentMap) -> MapDistribution {
        let (w, h) = (map.image.width(), map.image.height());
        let columns: Vec<Discrete> = (0..h)
            .map(|y| {
                let sin = (PI * (y as f64 + 0.5) / h as f64).sin();
                let weights: Vec<f64> =
                    (0..w).map(|x| luminance(map.image.texel(x, y)).max(0.0) * sin).collect();
                Discrete::new(&weights)
            })
            .collect();
        let rows = Discrete::new(&columns.iter().map(Discrete::total).collect::<Vec<_>>());
        MapDistribution { rows, columns }
    }

    /// A direction and its density per steradian.
    fn sample(&self, map: &EnvironmentMap, u1: f64, u2: f64) -> Option<(DVec3, f64)> {
        let (w, h) = (map.image.width() as f64, map.image.height() as f64);
        let (row, p_row, v_in) = self.rows.sample_remapped(u2)?;
        let (column, p_column, u_in) = self.columns[row].sample_remapped(u1)?;
        let (u, v) = ((column as f64 + u_in) / w, (row as f64 + v_in) / h);
        let (dir, sin) = map.direction(u, v);
        if sin <= 0.0 {
            return None;
        }
        Some((dir, p_row * p_column * w * h / (2.0 * PI * PI * sin)))
    }

    /// The density of [`MapDistribution::sample`] for `dir`.
    fn pdf(&self, map: &EnvironmentMap, dir: DVec3) -> f64 {
        let (w, h) = (map.image.width(), map.image.height());
        let (u, v) = map.uv(dir);
        let column = ((u * w as f64) as u32).min(w - 1) as usize;
        let row = ((v * h as f64) as u32).min(h - 1) as usize;
        let local_y = (map.to_local * dir).y.clamp(-1.0, 1.0);
        let sin = (1.0 - local_y * local_y).sqrt();
        if sin <= 0.0 {
            return 0.0;
        }
        self.rows.pmf(row) * self.columns[row].pmf(column) * (w as f64 * h as f64) / (2.0 * PI * PI * sin)
    }
}

/// The mean of an area emitter's radiance for choosing among emitters: a colour's mean, a
/// texture's mean over a grid of its texture coordinates, or 1 where that is not known (a mesh
/// attribute) or not positive (so that a textured light is still chosen).
fn mean_radiance(scene: &PreparedScene, radiance: &Param) -> f64 {
    match radiance {
        Param::Constant(c) => channel_mean(*c),
        Param::Texture(t) => {
            let m = texture_mean(scene, t);
            if m > 0.0 && m.is_finite() { m } else { 1.0 }
        }
    }
}

/// The mean of a texture's channel means over a grid of [`TEXTURE_MEAN_GRID`] squared texture
/// coordinates (cell centres), for power estimates.
fn texture_mean(scene: &PreparedScene, t: &Arc<TextureSpec>) -> f64 {
    let n = TEXTURE_MEAN_GRID;
    let mut sum = 0.0;
    for j in 0..n {
        for i in 0..n {
            let (u, v) = ((i as f64 + 0.5) / n as f64, (j as f64 + 0.5) / n as f64);
            sum += channel_mean(scene.texture_at(t, u, v));
        }
    }
    sum / (n * n) as f64
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A projector at the origin looking along `+z` with a 90 degree field of view, irradiance
    /// `e` and `scale` 2, in a scene with one small sphere far off (so that it is the only
    /// emitter chosen).
    fn scene(e: &str) -> PreparedScene {
        let text = format!(
            r#"<scene version="3.0.0">
<sensor type="perspective"><transform name="to_world"><lookat origin="0, 0, -5" target="0, 0, 0" up="0, 1, 0"/></transform>
    <film type="hdrfilm"><integer name="width" value="8"/><integer name="height" value="8"/></film></sensor>
<emitter type="projector"><float name="fov" value="90"/><float name="scale" value="2"/>{e}</emitter>
<shape type="sphere"><float name="radius" value="0.1"/><point name="center" value="0, 0, 50"/></shape>
</scene>"#
        );
        let doc =
            crate::scene::mitsuba::read_source(crate::scene::SourceFile::from_text("t.xml", None, text), &[])
                .expect("reads");
        let built = crate::scene::mitsuba::build(&doc).expect("builds");
        PreparedScene::new(built.scene, &Default::default()).expect("prepares")
    }

    #[test]
    fn a_projector_gives_pi_scale_e_at_distance_one_and_follows_mitsubas_normalisation() {
        let s = scene(r#"<rgb name="irradiance" value="1, 2, 3"/>"#);
        let emitters = Emitters::new(&s);
        // On the axis at distance 2: pi scale E / (z^2 cos) with z = 2, cos = 1.
        let on_axis = emitters.sample(DVec3::new(0.0, 0.0, 2.0), 0.5, 0.5, 0.5).expect("lit");
        assert!(on_axis.delta && (on_axis.pdf - 1.0).abs() < 1e-12);
        assert!((on_axis.wi - -DVec3::Z).length() < 1e-12);
        let expected = DVec3::new(1.0, 2.0, 3.0) * (2.0 * PI / 4.0);
        assert!((on_axis.radiance - expected).length() < 1e-12, "{}", on_axis.radiance);
        // Off the axis, on the plane z = 1: z^2 cos = cos, the irradiance on the plane
        // (radiance times the cosine at the plane) is pi scale E everywhere.
        let p = DVec3::new(0.6, -0.3, 1.0);
        let off = emitters.sample(p, 0.5, 0.5, 0.5).expect("lit");
        let cos = p.z / p.length();
        assert!((off.radiance * cos - DVec3::new(1.0, 2.0, 3.0) * 2.0 * PI).length() < 1e-9);
        // Outside the field of view, and behind: dark.
        assert!(emitters.sample(DVec3::new(1.01, 0.0, 1.0), 0.5, 0.5, 0.5).is_none());
        assert!(emitters.sample(DVec3::new(0.0, 0.0, -1.0), 0.5, 0.5, 0.5).is_none());
    }

    #[test]
    fn a_projected_texture_is_read_at_mitsubas_image_coordinates() {
        // A checkerboard of 2 x 2 squares: `color0` where u and v are both under 0.5 (and both
        // over). Local `+x` is towards u = 0, `+y` towards v = 0.
        let s = scene(
            r#"<texture type="checkerboard" name="irradiance"><rgb name="color0" value="1"/><rgb name="color1" value="0"/></texture>"#,
        );
        let emitters = Emitters::new(&s);
        let at = |x: f64, y: f64| emitters.sample(DVec3::new(x, y, 1.0), 0.5, 0.5, 0.5).map(|e| e.radiance.x);
        assert!(at(0.5, 0.5).is_some_and(|r| r > 0.0), "u, v < 0.5");
        assert!(at(-0.5, -0.5).is_some_and(|r| r > 0.0), "u, v > 0.5");
        assert_eq!(at(0.5, -0.5), Some(0.0));
        assert_eq!(at(-0.5, 0.5), Some(0.0));
    }
}
