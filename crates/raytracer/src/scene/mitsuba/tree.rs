//! The plugin tree: what a Mitsuba scene file says, as plain data, every item with its place.

use glam::{DMat4, DVec3};

use super::spectrum::Spectrum;
use crate::scene::Span;

/// Where an element or attribute is: the file (an index into [`super::Document::files`]) and the
/// line, column and length of the marked text.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct Pos {
    /// Index of the file in [`super::Document::files`] (0 is the file read first).
    pub file: u32,
    /// 1-based line and column (in characters) and length.
    pub span: Span,
}

/// The kind of a plugin: the XML element that declared it.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum PluginKind {
    /// `<scene>`: the root of a scene file.
    Scene,
    /// `<bsdf>`: a surface's scattering model.
    Bsdf,
    /// `<texture>`, or `<spectrum type="...">` (Mitsuba's spectra are textures).
    Texture,
    /// `<emitter>`: a light.
    Emitter,
    /// `<shape>`: geometry.
    Shape,
    /// `<sensor>`: a camera.
    Sensor,
    /// `<film>`: the image a sensor records.
    Film,
    /// `<rfilter>`: the film's reconstruction filter.
    ReconstructionFilter,
    /// `<sampler>`: the sample generator (its `sample_count` is the samples per pixel).
    Sampler,
    /// `<integrator>`: the light-transport algorithm.
    Integrator,
    /// `<medium>`: a participating medium.
    Medium,
    /// `<phase>`: a medium's phase function.
    Phase,
    /// `<volume>`: a 3D texture of a medium.
    Volume,
}

impl PluginKind {
    /// The kind an object element names (`"bsdf"`, ...), `None` for other elements.
    pub fn from_tag(tag: &str) -> Option<PluginKind> {
        Some(match tag {
            "scene" => PluginKind::Scene,
            "bsdf" => PluginKind::Bsdf,
            "texture" => PluginKind::Texture,
            "emitter" => PluginKind::Emitter,
            "shape" => PluginKind::Shape,
            "sensor" => PluginKind::Sensor,
            "film" => PluginKind::Film,
            "rfilter" => PluginKind::ReconstructionFilter,
            "sampler" => PluginKind::Sampler,
            "integrator" => PluginKind::Integrator,
            "medium" => PluginKind::Medium,
            "phase" => PluginKind::Phase,
            "volume" => PluginKind::Volume,
            _ => return None,
        })
    }

    /// The element name, as scene files write it.
    pub fn tag(self) -> &'static str {
        match self {
            PluginKind::Scene => "scene",
            PluginKind::Bsdf => "bsdf",
            PluginKind::Texture => "texture",
            PluginKind::Emitter => "emitter",
            PluginKind::Shape => "shape",
            PluginKind::Sensor => "sensor",
            PluginKind::Film => "film",
            PluginKind::ReconstructionFilter => "rfilter",
            PluginKind::Sampler => "sampler",
            PluginKind::Integrator => "integrator",
            PluginKind::Medium => "medium",
            PluginKind::Phase => "phase",
            PluginKind::Volume => "volume",
        }
    }
}

/// One plugin of the scene: a `<bsdf type="diffuse">`, a `<shape type="obj">`, the `<scene>`...
/// Its properties and nested plugins are in file order (after includes are spliced in).
#[derive(Clone, Debug, PartialEq)]
pub struct Plugin {
    /// The element that declared it.
    pub kind: PluginKind,
    /// The plugin's `type` (`"diffuse"`, `"obj"`, ...); `"scene"` for the scene.
    pub type_name: String,
    /// Its `id`, by which `<ref>` elements name it.
    pub id: Option<String>,
    /// Its `name` under its parent (the parameter it fills, e.g. `"reflectance"`), if given.
    pub name: Option<String>,
    /// The typed properties (`<float>`, `<rgb>`, `<transform>`...), in file order.
    pub properties: Vec<Property>,
    /// The nested plugins and references, in file order.
    pub children: Vec<Child>,
    /// Where the element starts (its tag name).
    pub pos: Pos,
}

impl Plugin {
    /// The property called `name`, if the plugin has one.
    pub fn property(&self, name: &str) -> Option<&Property> {
        self.properties.iter().find(|p| p.name == name)
    }

    /// The nested plugin or reference that fills the parameter `name`, if any.
    pub fn child(&self, name: &str) -> Option<&Child> {
        self.children.iter().find(|c| c.name.as_deref() == Some(name))
    }

    /// The nested plugins and references, with inline plugins only (references skipped).
    pub fn inline_children(&self) -> impl Iterator<Item = &Plugin> {
        self.children.iter().filter_map(|c| match &c.node {
            Node::Plugin(p) => Some(p),
            Node::Reference(_) => None,
        })
    }

    /// Every plugin declared in this one's subtree, this one first (depth first, file order);
    /// references are not followed.
    pub fn descendants(&self) -> Vec<&Plugin> {
        let mut out = Vec::new();
        let mut stack = vec![self];
        while let Some(p) = stack.pop() {
            out.push(p);
            let start = stack.len();
            stack.extend(p.inline_children());
            stack[start..].reverse();
        }
        out
    }
}

/// A nested plugin or a reference to one, as a parameter of its parent.
#[derive(Clone, Debug, PartialEq)]
pub struct Child {
    /// The parameter it fills (`name="..."`), if given; Mitsuba names the others `_arg_N`.
    pub name: Option<String>,
    /// The plugin, or the `id` it refers to.
    pub node: Node,
    /// Where the element (the plugin or the `<ref>`) starts.
    pub pos: Pos,
}

/// What a [`Child`] holds.
#[derive(Clone, Debug, PartialEq)]
pub enum Node {
    /// A plugin declared in place.
    Plugin(Plugin),
    /// `<ref id="..."/>`: a plugin declared elsewhere (see [`super::Document::target`]). Every
    /// id is checked to exist when the file is read.
    Reference(String),
}

/// A named, typed parameter of a plugin.
#[derive(Clone, Debug, PartialEq)]
pub struct Property {
    /// The parameter name (`name="..."`), snake_case (older files are upgraded).
    pub name: String,
    /// The value.
    pub value: Value,
    /// Where the element starts.
    pub pos: Pos,
}

/// A property's value.
#[derive(Clone, Debug, PartialEq)]
pub enum Value {
    /// `<integer>`: a signed 64-bit integer.
    Integer(i64),
    /// `<float>`: a finite number.
    Float(f64),
    /// `<boolean>`: `true` or `false` (any case).
    Boolean(bool),
    /// `<string>`: the text as written (after `$name` substitution).
    String(String),
    /// `<rgb>`: a linear RGB triple (one value is repeated three times).
    Rgb(DVec3),
    /// `<spectrum>`: a uniform value or a sampled spectrum (see [`Spectrum::to_srgb`]).
    Spectrum(Spectrum),
    /// `<point>`: a position, world units (z-up in rayterra, as Mitsuba writes it).
    Point(DVec3),
    /// `<vector>`: a direction or extent.
    Vector(DVec3),
    /// `<transform>`: the composed matrix (column vectors: `p' = M p`); never singular.
    Transform(DMat4),
}

impl Value {
    /// The XML element that declares a value of this type.
    pub fn tag(&self) -> &'static str {
        match self {
            Value::Integer(_) => "integer",
            Value::Float(_) => "float",
            Value::Boolean(_) => "boolean",
            Value::String(_) => "string",
            Value::Rgb(_) => "rgb",
            Value::Spectrum(_) => "spectrum",
            Value::Point(_) => "point",
            Value::Vector(_) => "vector",
            Value::Transform(_) => "transform",
        }
    }
}
