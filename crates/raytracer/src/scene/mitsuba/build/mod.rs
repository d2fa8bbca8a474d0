//! From a Mitsuba plugin tree ([`Document`]) to the scene description every model reads
//! ([`Scene`]): the sensor becomes the camera and the render settings, shapes become primitives
//! (meshes read here, in world space), BSDFs become [`Material`]s, emitters become
//! [`Emitter`]s. Plugins rayterra does not have are warnings naming the plugin and its line, and
//! the render goes on without them; where going on would show something else than Mitsuba
//! would (a sensor type we lack), they are errors.
//!
//! World space is the file's own: Mitsuba scenes are often y-up, and the camera's `up` comes from
//! its `to_world`, so nothing is rotated.

mod bsdfs;
mod emitters;
mod ior;
mod props;
mod sensor;
mod shapes;
mod textures;

#[cfg(test)]
mod tests;

use std::collections::HashMap;
use std::path::PathBuf;
use std::sync::Arc;

use super::{Document, Plugin, PluginKind};
use crate::light::Emitter;
use crate::material::{Material, Param, TextureSpec};
use crate::scene::{Background, CameraSettings, Diagnostic, DirectSamples, Scene, SceneRender, Severity};
pub use ior::{METALS, NAMED_IORS, metal_ior, named_ior};
use props::Props;

/// A Mitsuba scene built: the scene, the warnings and notes found on the way, and the files it
/// read (mesh files; textures are read when the scene is prepared).
#[derive(Debug)]
pub struct Built {
    /// The scene.
    pub scene: Scene,
    /// Warnings and notes, in file order.
    pub diagnostics: Vec<Diagnostic>,
    /// The mesh files read.
    pub inputs: Vec<PathBuf>,
}

/// Builds the scene of a Mitsuba document. Every error found is returned (with the warnings
/// before it); a scene is built only when there is none.
pub fn build(doc: &Document) -> Result<Built, Vec<Diagnostic>> {
    let mut b = Builder {
        doc,
        scene: Scene {
            background: Background::default(),
            camera: CameraSettings::default(),
            lights: Vec::new(),
            primitives: Vec::new(),
            meshes: Vec::new(),
            emitters: Vec::new(),
            render: SceneRender { srgb_output: true, ..SceneRender::default() },
        },
        diagnostics: Vec::new(),
        inputs: Vec::new(),
        materials: HashMap::new(),
        textures: HashMap::new(),
        sensor_seen: false,
        triangles: 0,
    };
    b.diagnostics.extend(doc.warnings.iter().cloned());
    let root = &doc.root;
    let root_props = Props::new(doc, root);
    for (child, plugin) in doc.children(root) {
        let _ = child;
        let result = match plugin.kind {
            PluginKind::Integrator => b.integrator(plugin),
            PluginKind::Sensor => b.sensor(plugin),
            PluginKind::Shape => b.shape(plugin, None),
            // An area emitter declared by id is built in the shape that refers to it.
            PluginKind::Emitter if plugin.type_name == "area" && plugin.id.is_some() => Ok(()),
            PluginKind::Emitter => b.emitter(plugin),
            // Declared for reference by id; built where they are used.
            PluginKind::Bsdf
            | PluginKind::Texture
            | PluginKind::Film
            | PluginKind::Sampler
            | PluginKind::ReconstructionFilter => Ok(()),
            PluginKind::Medium | PluginKind::Phase | PluginKind::Volume if plugin.id.is_some() => Ok(()),
            _ => {
                b.warn(
                    &Props::new(doc, plugin),
                    "rayterra has no such plugin; the scene is rendered without it",
                );
                Ok(())
            }
        };
        if let Err(e) = result {
            b.diagnostics.push(e);
        }
    }
    b.diagnostics.extend(root_props.unread());
    if !b.sensor_seen {
        b.diagnostics.push(root_props.error(
            "the scene has no <sensor>: add a `perspective` sensor with a `to_world` transform, a film and a sampler",
        ));
    }
    if b.diagnostics.iter().any(Diagnostic::is_error) {
        return Err(b.diagnostics);
    }
    Ok(Built { scene: b.scene, diagnostics: b.diagnostics, inputs: b.inputs })
}

/// Most samples of each strategy of the `direct` integrator.
pub const MAX_DIRECT_SAMPLES: u32 = 1 << 16;

/// The state of a build.
struct Builder<'a> {
    doc: &'a Document,
    scene: Scene,
    diagnostics: Vec<Diagnostic>,
    inputs: Vec<PathBuf>,
    /// Materials built, by plugin (a BSDF referenced by several shapes is built once).
    materials: HashMap<*const Plugin, Arc<Material>>,
    /// Textures built, by plugin.
    textures: HashMap<*const Plugin, Arc<TextureSpec>>,
    /// Whether a sensor was read (the first one is used).
    sensor_seen: bool,
    /// Triangles of the meshes built so far.
    triangles: usize,
}

impl<'a> Builder<'a> {
    /// A warning about a plugin rayterra does not render, naming it.
    fn warn(&mut self, props: &Props<'_>, consequence: &str) {
        let p = props.plugin;
        let message = format!("the {} `{}` is not supported: {consequence}", p.kind.tag(), p.type_name);
        self.diagnostics.push(props.warning(message));
    }

    /// A note (the render goes on as Mitsuba's would, in expectation).
    fn note(&mut self, props: &Props<'_>, message: impl Into<String>) {
        let mut d = props.warning(message);
        d.severity = Severity::Note;
        self.diagnostics.push(d);
    }

    /// Reports the properties of `props` nobody read.
    fn finish(&mut self, props: &Props<'_>) {
        self.diagnostics.extend(props.unread());
    }

    /// A colour or texture parameter: `<rgb name>`/`<spectrum name>`/`<float name>`, or a
    /// nested or referenced `<texture name>`; `default` (grey) when absent.
    fn param(&mut self, props: &Props<'a>, name: &str, default: f64) -> Result<Param, Diagnostic> {
        if let Some(c) = props.color(name)? {
            return Ok(Param::Constant(c));
        }
        match props.named_child(name) {
            None => Ok(Param::scalar(default)),
            Some(t) if t.kind == PluginKind::Texture => self.texture(t),
            Some(other) => Err(props.error_at(
                other.pos,
                format!("`{name}` must be a colour or a <texture>, not a <{}>", other.kind.tag()),
            )),
        }
    }

    /// A scalar parameter (a roughness, an opacity, a weight), read as [`Builder::param`] reads a
    /// colour, but for one quirk of Mitsuba 3 (3.9.1): its `checkerboard` gives scalar reads
    /// (`eval_1`) the other phase than colour reads (`eval`), `color1` where `color0` would be.
    /// A checkerboard read as a scalar is built with its colours swapped, so that it reads as
    /// Mitsuba reads it.
    fn scalar_param(&mut self, props: &Props<'a>, name: &str, default: f64) -> Result<Param, Diagnostic> {
        Ok(match self.param(props, name, default)? {
            Param::Texture(t) => match &*t {
                TextureSpec::Checkerboard { color0, color1, to_uv } => {
                    Param::Texture(Arc::new(TextureSpec::Checkerboard {
                        color0: *color1,
                        color1: *color0,
                        to_uv: *to_uv,
                    }))
                }
                _ => Param::Texture(t),
            },
            constant => constant,
        })
    }

    /// `<integrator>`: the path tracer's settings.
    fn integrator(&mut self, plugin: &'a Plugin) -> Result<(), Diagnostic> {
        let props = Props::new(self.doc, plugin);
        match props.type_name() {
            "path" => self.path_settings(&props)?,
            "direct" => {
                let count = |name: &str, default: i64| -> Result<u32, Diagnostic> {
                    let n = props.integer(name, default)?;
                    u32::try_from(n).ok().filter(|&n| n <= MAX_DIRECT_SAMPLES).ok_or_else(|| {
                        props.error(format!("`{name}` must be from 0 to {MAX_DIRECT_SAMPLES}, not {n}"))
                    })
                };
                let shading = props.get("shading_samples").is_some();
                if shading && (props.get("emitter_samples").is_some() || props.get("bsdf_samples").is_some())
                {
                    return Err(props.error(
                        "give `shading_samples` or `emitter_samples` and `bsdf_samples`, not both (as Mitsuba)",
                    ));
                }
                let both = count("shading_samples", 1)?;
                let samples = DirectSamples {
                    emitter_samples: count("emitter_samples", both as i64)?,
                    bsdf_samples: count("bsdf_samples", both as i64)?,
                };
                if samples.emitter_samples + samples.bsdf_samples == 0 {
                    return Err(
                        props.error("the `direct` integrator needs at least one emitter or BSDF sample")
                    );
                }
                self.scene.render.direct = Some(samples);
                // Direct lighting: paths of two segments.
                self.scene.render.max_depth = Some(2);
                self.scene.render.hide_emitters = props.boolean("hide_emitters", false)?;
            }
            "aov" | "moment" => {
                let nested = props.children(PluginKind::Integrator);
                self.note(
                    &props,
                    format!("the `{}` integrator's nested integrator is rendered", props.type_name()),
                );
                props.ignore("aovs");
                match nested.first() {
                    Some((_, inner)) => return self.integrator(inner),
                    None => self.scene.render = SceneRender { srgb_output: true, ..SceneRender::default() },
                }
            }
            "volpath" | "volpathmis" | "prb" | "prbvolpath" | "ptracer" => {
                self.path_settings(&props)?;
                let name = props.type_name().to_owned();
                self.warn(
                    &props,
                    &format!("the scene is rendered with the `path` integrator instead of `{name}`"),
                );
            }
            _ => {
                self.warn(&props, "the scene is rendered with the `path` integrator");
            }
        }
        self.finish(&props);
        Ok(())
    }

    /// `max_depth`, `rr_depth` and `hide_emitters` of a path integrator.
    fn path_settings(&mut self, props: &Props<'_>) -> Result<(), Diagnostic> {
        let depth = props.integer("max_depth", -1)?;
        self.scene.render.max_depth = Some(match depth {
            -1 => u32::MAX,
            d if d >= 0 => d.min(u32::MAX as i64 - 1) as u32,
            d => {
                return Err(props.error(format!("`max_depth` must be -1 (unbounded) or at least 0, not {d}")));
            }
        });
        let rr = props.integer("rr_depth", 5)?;
        if rr < 1 {
            return Err(props.error(format!("`rr_depth` must be at least 1, not {rr}")));
        }
        self.scene.render.rr_depth = rr.min(u32::MAX as i64) as u32;
        self.scene.render.hide_emitters = props.boolean("hide_emitters", false)?;
        Ok(())
    }

    /// The material of a shape: its nested or referenced BSDF, or Mitsuba's default: diffuse of
    /// reflectance 0.5, or 0 (black) for a shape that emits.
    fn shape_material(&mut self, props: &Props<'a>) -> Result<Arc<Material>, Diagnostic> {
        match props.children(PluginKind::Bsdf).first() {
            Some((_, bsdf)) => self.material(bsdf),
            None => {
                let emits = !props.children(PluginKind::Emitter).is_empty();
                let reflectance = if emits { 0.0 } else { 0.5 };
                Ok(Arc::new(Material::Diffuse { reflectance: Param::scalar(reflectance) }))
            }
        }
    }

    /// Adds an emitter.
    fn push_emitter(&mut self, e: Emitter) {
        self.scene.emitters.push(e);
    }
}
