//! Scene-format versions and the upgrades Mitsuba 3 applies to files older than 2.0.0.
//!
//! Mitsuba 3 (`src/core/parser.cpp`, `upgrade_from_v1`, applied to every plugin of a file whose
//! `version` is below 2.0.0; the older reader, `src/core/xml.cpp`, did the same) renames:
//!
//! - every parameter name from camelCase to snake_case (`fovAxis` -> `fov_axis`,
//!   `intIOR` -> `int_ior`): [`camel_to_snake`], applied by the reader to the `name` of every
//!   property, nested plugin and `<ref>` of such a file (not to `<default>` names);
//! - `diffuse_reflectance` -> `reflectance` in `diffuse` BSDFs: [`upgrade_plugin`];
//! - the floats `uoffset`, `voffset`, `uscale`, `vscale` into a `to_uv` transform,
//!   `scale(uscale, vscale, 1) * translate(uoffset, voffset, 0)`: [`upgrade_plugin`].
//!
//! The older reader also renamed the element `<lookAt>` to `<lookat>`; so does ours (in
//! `<transform>`s of files below 2.0.0). Files of 2.x and 3.x are read as they are.

use glam::{DMat4, DVec3};

use super::tree::{Plugin, Property, Value};

/// A scene-format version, `major.minor.patch`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub struct Version {
    /// Major version (0 for Mitsuba 0.x files, 2 or 3 for current ones).
    pub major: u32,
    /// Minor version.
    pub minor: u32,
    /// Patch version.
    pub patch: u32,
}

impl Version {
    /// The first version whose files need no upgrade.
    pub const V2: Version = Version { major: 2, minor: 0, patch: 0 };

    /// Parses `major.minor.patch`; `major` and `major.minor` are taken with the missing parts
    /// zero. White space around the text is allowed.
    pub fn parse(text: &str) -> Option<Version> {
        let mut parts = text.trim().split('.');
        let mut next = |required: bool| match parts.next() {
            Some(p) if !p.is_empty() && p.bytes().all(|b| b.is_ascii_digit()) => p.parse::<u32>().ok(),
            None if !required => Some(0),
            _ => None,
        };
        let version = Version { major: next(true)?, minor: next(false)?, patch: next(false)? };
        parts.next().is_none().then_some(version)
    }

    /// Whether files of this version are upgraded (below 2.0.0).
    pub fn needs_upgrade(self) -> bool {
        self < Version::V2
    }
}

impl std::fmt::Display for Version {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "{}.{}.{}", self.major, self.minor, self.patch)
    }
}

/// camelCase to snake_case as Mitsuba 3 converts parameter names: an upper-case letter after a
/// lower-case one starts a new word (`_` and the letter in lower case), and the upper-case
/// letters right after it join that word (`intIOR` -> `int_ior`, `sampleCount` ->
/// `sample_count`). Anything else is kept.
pub fn camel_to_snake(name: &str) -> String {
    let chars: Vec<char> = name.chars().collect();
    let mut out = String::with_capacity(name.len() + 4);
    let mut i = 0;
    while i < chars.len() {
        let c = chars[i];
        if i > 0 && chars[i - 1].is_ascii_lowercase() && c.is_ascii_uppercase() {
            out.push('_');
            out.push(c.to_ascii_lowercase());
            while i + 1 < chars.len() && chars[i + 1].is_ascii_uppercase() {
                i += 1;
                out.push(chars[i].to_ascii_lowercase());
            }
        } else {
            out.push(c);
        }
        i += 1;
    }
    out
}

/// The per-plugin upgrades of a file below 2.0.0 (after the names were converted): a diffuse
/// BSDF's `diffuse_reflectance`, and texture offsets and scales into `to_uv`. Offsets and scales
/// given as integers are taken as numbers too; other types are left alone.
pub fn upgrade_plugin(plugin: &mut Plugin) {
    if plugin.type_name == "diffuse" {
        for p in &mut plugin.properties {
            if p.name == "diffuse_reflectance" {
                p.name = "reflectance".into();
            }
        }
        for c in &mut plugin.children {
            if c.name.as_deref() == Some("diffuse_reflectance") {
                c.name = Some("reflectance".into());
            }
        }
    }
    let number = |p: &Property| match p.value {
        Value::Float(v) => Some(v),
        Value::Integer(v) => Some(v as f64),
        _ => None,
    };
    let mut offset = DVec3::ZERO;
    let mut scale = DVec3::ONE;
    let mut first = None;
    plugin.properties.retain(|p| {
        let slot = match p.name.as_str() {
            "uoffset" => &mut offset.x,
            "voffset" => &mut offset.y,
            "uscale" => &mut scale.x,
            "vscale" => &mut scale.y,
            _ => return true,
        };
        match number(p) {
            Some(v) => {
                *slot = v;
                first.get_or_insert(p.pos);
                false
            }
            None => true,
        }
    });
    if let Some(pos) = first {
        let matrix = DMat4::from_scale(scale) * DMat4::from_translation(offset);
        plugin.properties.push(Property { name: "to_uv".into(), value: Value::Transform(matrix), pos });
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn versions_parse() {
        assert_eq!(Version::parse("3.0.0"), Some(Version { major: 3, minor: 0, patch: 0 }));
        assert_eq!(Version::parse(" 0.6 "), Some(Version { major: 0, minor: 6, patch: 0 }));
        for bad in ["", "3.", "3.0.0.1", "a.b.c", "-1.0.0", "3 0 0"] {
            assert_eq!(Version::parse(bad), None, "{bad:?}");
        }
        assert!(Version::parse("0.6.0").is_some_and(Version::needs_upgrade));
        assert!(Version::parse("1.9.9").is_some_and(Version::needs_upgrade));
        assert!(!Version::parse("2.0.0").is_some_and(Version::needs_upgrade));
    }

    #[test]
    fn camel_case_becomes_snake_case_as_mitsuba_converts_it() {
        for (from, to) in [
            ("fovAxis", "fov_axis"),
            ("intIOR", "int_ior"),
            ("sampleCount", "sample_count"),
            ("maxDepth", "max_depth"),
            ("aBcD", "a_bc_d"),
            ("already_snake", "already_snake"),
            ("Upper", "Upper"),
            ("toWorld", "to_world"),
            ("", ""),
        ] {
            assert_eq!(camel_to_snake(from), to, "{from}");
        }
    }
}
