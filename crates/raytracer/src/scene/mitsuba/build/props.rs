//! Typed reads of a plugin's properties, with Mitsuba's defaults, each error at the property's
//! place, and a record of what was read so that unread properties can be reported.

use std::cell::RefCell;

use glam::{DMat4, DVec3};

use super::super::{Document, Plugin, PluginKind, Pos, SpectrumUse, Value};
use crate::scene::{Diagnostic, Severity};

/// The properties of one plugin, read by name.
pub(super) struct Props<'a> {
    pub doc: &'a Document,
    pub plugin: &'a Plugin,
    /// Names read so far (properties and named children).
    read: RefCell<Vec<&'a str>>,
    /// Whether the plugin sits inside an emitter (its spectra are emission).
    within_emitter: bool,
}

impl<'a> Props<'a> {
    pub fn new(doc: &'a Document, plugin: &'a Plugin) -> Props<'a> {
        Props::with_emission(doc, plugin, plugin.kind == PluginKind::Emitter)
    }

    /// As [`Props::new`], saying whether the plugin is (or is inside) an emitter.
    pub fn with_emission(doc: &'a Document, plugin: &'a Plugin, within_emitter: bool) -> Props<'a> {
        Props { doc, plugin, read: RefCell::new(Vec::new()), within_emitter }
    }

    /// An error at `pos`.
    pub fn error_at(&self, pos: Pos, message: impl Into<String>) -> Diagnostic {
        Diagnostic {
            severity: Severity::Error,
            message: message.into(),
            location: Some(self.doc.location(pos)),
            notes: Vec::new(),
        }
    }

    /// An error at the plugin.
    pub fn error(&self, message: impl Into<String>) -> Diagnostic {
        self.error_at(self.plugin.pos, message)
    }

    /// A warning at the plugin.
    pub fn warning(&self, message: impl Into<String>) -> Diagnostic {
        Diagnostic { severity: Severity::Warning, ..self.error(message) }
    }

    /// The plugin's `type`.
    pub fn type_name(&self) -> &'a str {
        &self.plugin.type_name
    }

    /// The property called `name`, marked as read.
    pub fn get(&self, name: &str) -> Option<&'a super::super::Property> {
        let p = self.plugin.property(name)?;
        self.read.borrow_mut().push(&p.name);
        Some(p)
    }

    /// Marks `name` as read without reading it (a parameter that is understood and has no
    /// effect on the picture, such as a film's pixel format).
    pub fn ignore(&self, name: &str) {
        let _ = self.get(name);
    }

    /// A number (`<float>` or `<integer>`).
    pub fn float(&self, name: &str, default: f64) -> Result<f64, Diagnostic> {
        match self.get(name) {
            None => Ok(default),
            Some(p) => match p.value {
                Value::Float(x) => Ok(x),
                Value::Integer(i) => Ok(i as f64),
                ref other => Err(self.wrong_type(p.pos, name, "a <float>", other)),
            },
        }
    }

    /// A number that must be positive and finite.
    pub fn positive(&self, name: &str, default: f64) -> Result<f64, Diagnostic> {
        let x = self.float(name, default)?;
        if x > 0.0 && x.is_finite() {
            Ok(x)
        } else {
            let pos = self.plugin.property(name).map_or(self.plugin.pos, |p| p.pos);
            Err(self.error_at(pos, format!("`{name}` must be a positive number, not {x}")))
        }
    }

    /// An `<integer>`.
    pub fn integer(&self, name: &str, default: i64) -> Result<i64, Diagnostic> {
        match self.get(name) {
            None => Ok(default),
            Some(p) => match p.value {
                Value::Integer(i) => Ok(i),
                ref other => Err(self.wrong_type(p.pos, name, "an <integer>", other)),
            },
        }
    }

    /// A `<boolean>`.
    pub fn boolean(&self, name: &str, default: bool) -> Result<bool, Diagnostic> {
        match self.get(name) {
            None => Ok(default),
            Some(p) => match p.value {
                Value::Boolean(b) => Ok(b),
                ref other => Err(self.wrong_type(p.pos, name, "a <boolean>", other)),
            },
        }
    }

    /// A `<string>`, with where it is.
    pub fn string(&self, name: &str) -> Result<Option<(&'a str, Pos)>, Diagnostic> {
        match self.get(name) {
            None => Ok(None),
            Some(p) => match &p.value {
                Value::String(s) => Ok(Some((s.as_str(), p.pos))),
                other => Err(self.wrong_type(p.pos, name, "a <string>", other)),
            },
        }
    }

    /// A `<string>` that must be one of `choices`, or `default`.
    pub fn choice(
        &self,
        name: &str,
        choices: &[&'static str],
        default: &'static str,
    ) -> Result<&'a str, Diagnostic> {
        match self.string(name)? {
            None => Ok(default),
            Some((s, pos)) if choices.contains(&s) => {
                let _ = pos;
                Ok(s)
            }
            Some((s, pos)) => Err(self.error_at(
                pos,
                format!(
                    "`{name}` is `{}`; it must be one of {}",
                    crate::base::diagnostic::clip(s),
                    choices.iter().map(|c| format!("`{c}`")).collect::<Vec<_>>().join(", ")
                ),
            )),
        }
    }

    /// A `<point>` or `<vector>`.
    pub fn vector(&self, name: &str, default: DVec3) -> Result<DVec3, Diagnostic> {
        match self.get(name) {
            None => Ok(default),
            Some(p) => match p.value {
                Value::Point(v) | Value::Vector(v) => Ok(v),
                ref other => Err(self.wrong_type(p.pos, name, "a <point> or <vector>", other)),
            },
        }
    }

    /// A `<transform>` (the identity when absent).
    pub fn transform(&self, name: &str) -> Result<DMat4, Diagnostic> {
        match self.get(name) {
            None => Ok(DMat4::IDENTITY),
            Some(p) => match p.value {
                Value::Transform(m) => Ok(m),
                ref other => Err(self.wrong_type(p.pos, name, "a <transform>", other)),
            },
        }
    }

    /// A colour: `<rgb>`, `<spectrum>` (reduced to RGB as Mitsuba's RGB variants do for what
    /// the parameter is used for) or `<float>` (grey). `None` when absent.
    pub fn color(&self, name: &str) -> Result<Option<DVec3>, Diagnostic> {
        let Some(p) = self.get(name) else { return Ok(None) };
        match &p.value {
            Value::Rgb(c) => Ok(Some(*c)),
            Value::Spectrum(s) => Ok(Some(s.to_srgb(SpectrumUse::of(name, self.within_emitter)))),
            Value::Float(x) => Ok(Some(DVec3::splat(*x))),
            Value::Integer(i) => Ok(Some(DVec3::splat(*i as f64))),
            other => Err(self.wrong_type(p.pos, name, "an <rgb>, <spectrum> or <float>", other)),
        }
    }

    /// The nested plugins (references followed) of `kind`, with the name they are given.
    pub fn children(&self, kind: PluginKind) -> Vec<(Option<&'a str>, &'a Plugin)> {
        self.doc
            .children(self.plugin)
            .filter(|(_, p)| p.kind == kind)
            .map(|(c, p)| {
                if let Some(n) = &c.name {
                    self.read.borrow_mut().push(n);
                }
                (c.name.as_deref(), p)
            })
            .collect()
    }

    /// The nested plugin given as parameter `name` (`<texture name="reflectance">` or
    /// `<ref name="reflectance" id=...>`).
    pub fn named_child(&self, name: &str) -> Option<&'a Plugin> {
        let (c, p) = self.doc.children(self.plugin).find(|(c, _)| c.name.as_deref() == Some(name))?;
        if let Some(n) = &c.name {
            self.read.borrow_mut().push(n);
        }
        Some(p)
    }

    /// Warnings for the properties that were never read: Mitsuba's "unreferenced property".
    pub fn unread(&self) -> Vec<Diagnostic> {
        let read = self.read.borrow();
        self.plugin
            .properties
            .iter()
            .filter(|p| !read.contains(&p.name.as_str()))
            .map(|p| {
                let mut d = self.error_at(
                    p.pos,
                    format!(
                        "the {} `{}` has no parameter `{}` that rayterra reads; it is ignored",
                        self.plugin.kind.tag(),
                        self.plugin.type_name,
                        p.name
                    ),
                );
                d.severity = Severity::Warning;
                d
            })
            .collect()
    }

    fn wrong_type(&self, pos: Pos, name: &str, expected: &str, got: &Value) -> Diagnostic {
        self.error_at(pos, format!("`{name}` must be {expected}, not a <{}>", got.tag()))
    }
}
