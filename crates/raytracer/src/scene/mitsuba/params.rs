//! Scene parameters: `$name` substitution in attribute values, `<default>`, and Mitsuba's
//! command-line `-D name=value`.

/// Longest attribute value after substitution, in bytes.
pub const MAX_SUBSTITUTED_BYTES: usize = 1 << 20;
/// Most parameters (`<default>`s and `-D` definitions) of one scene: each attribute with a `$`
/// is searched for each of them.
pub const MAX_PARAMETERS: usize = 1000;

/// A `-D` argument that is not `name=value`.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
pub enum DefineError {
    /// No `=`.
    #[error("`{0}` is not name=value")]
    NoEquals(String),
    /// The name is empty or has characters other than letters, digits and `_`.
    #[error("`{0}` is not a parameter name (letters, digits and _)")]
    BadName(String),
}

/// Parses a Mitsuba-style `-D` argument, `name=value`: the name is made of ASCII letters,
/// digits and `_`; the value is everything after the first `=` (it may be empty or hold `=`).
///
/// ```
/// use raytracer::scene::mitsuba::parse_define;
/// assert_eq!(parse_define("spp=64"), Ok(("spp".to_owned(), "64".to_owned())));
/// assert!(parse_define("spp").is_err());
/// ```
pub fn parse_define(arg: &str) -> Result<(String, String), DefineError> {
    let (name, value) = arg.split_once('=').ok_or_else(|| DefineError::NoEquals(arg.to_owned()))?;
    if name.is_empty() || !name.bytes().all(|b| b.is_ascii_alphanumeric() || b == b'_') {
        return Err(DefineError::BadName(name.to_owned()));
    }
    Ok((name.to_owned(), value.to_owned()))
}

/// One parameter: `$name`'s value, and whether an attribute used it.
#[derive(Clone, Debug)]
pub struct Param {
    /// `$` and the name.
    pub key: String,
    /// The value substituted.
    pub value: String,
    /// Whether some attribute used it (unused `-D` definitions draw a warning).
    pub used: bool,
    /// Whether it came from the caller (`-D`) rather than a `<default>`.
    pub from_caller: bool,
}

/// The parameters in force, longest key first (so that `$spp_max` is not read as `$spp`
/// followed by `_max`), as Mitsuba sorts them.
#[derive(Clone, Debug, Default)]
pub struct Params {
    list: Vec<Param>,
}

/// Why a substitution failed.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum SubstituteError {
    /// `$name` with no value; the name is the letters, digits and `_` after the `$`.
    Undefined(String),
    /// The result would pass [`MAX_SUBSTITUTED_BYTES`].
    TooLong,
}

impl Params {
    /// The caller's definitions (later ones of the same name win, as with repeated `-D`).
    pub fn from_defines(defines: &[(String, String)]) -> Params {
        let mut params = Params::default();
        for (name, value) in defines {
            let key = format!("${name}");
            match params.list.iter_mut().find(|p| p.key == key) {
                Some(p) => p.value = value.clone(),
                None => params.insert(Param { key, value: value.clone(), used: false, from_caller: true }),
            }
        }
        params
    }

    fn insert(&mut self, param: Param) {
        let at = self.list.iter().position(|p| param.key.len() > p.key.len()).unwrap_or(self.list.len());
        self.list.insert(at, param);
    }

    /// `<default name="..." value="...">`: sets the parameter unless the caller or an earlier
    /// `<default>` already did. `false` when there are [`MAX_PARAMETERS`] already.
    pub fn set_default(&mut self, name: &str, value: &str) -> bool {
        let key = format!("${name}");
        if !self.list.iter().any(|p| p.key == key) {
            if self.list.len() >= MAX_PARAMETERS {
                return false;
            }
            self.insert(Param { key, value: value.to_owned(), used: true, from_caller: false });
        }
        true
    }

    /// The caller's definitions that no attribute used, in the order given.
    pub fn unused(&self) -> impl Iterator<Item = &Param> {
        self.list.iter().filter(|p| p.from_caller && !p.used)
    }

    /// Substitutes every `$name` of `value` as Mitsuba 3 does: each parameter in turn, longest
    /// name first, replaces its key wherever it is not preceded by `\`; a `$` still unescaped
    /// then is an undefined parameter; `\$` finally becomes `$`. Returns `None` when `value`
    /// has no `$` (nothing to do).
    pub fn substitute(&mut self, value: &str) -> Option<Result<String, SubstituteError>> {
        if !value.contains('$') {
            return None;
        }
        let mut text = value.to_owned();
        for param in &mut self.list {
            let mut from = 0;
            while let Some(found) = text[from..].find(param.key.as_str()) {
                let pos = from + found;
                if pos > 0 && text.as_bytes()[pos - 1] == b'\\' {
                    from = pos + param.key.len();
                    continue;
                }
                if text.len() - param.key.len() + param.value.len() > MAX_SUBSTITUTED_BYTES {
                    return Some(Err(SubstituteError::TooLong));
                }
                text.replace_range(pos..pos + param.key.len(), &param.value);
                param.used = true;
                from = pos + param.value.len();
            }
        }
        let bytes = text.as_bytes();
        for (i, &b) in bytes.iter().enumerate() {
            if b == b'$' && (i == 0 || bytes[i - 1] != b'\\') {
                let name: String =
                    text[i + 1..].chars().take_while(|c| c.is_ascii_alphanumeric() || *c == '_').collect();
                return Some(Err(SubstituteError::Undefined(name)));
            }
        }
        Some(Ok(text.replace("\\$", "$")))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn defines(pairs: &[(&str, &str)]) -> Params {
        let owned: Vec<_> = pairs.iter().map(|(a, b)| (a.to_string(), b.to_string())).collect();
        Params::from_defines(&owned)
    }

    #[test]
    fn longest_names_are_substituted_first() {
        let mut p = defines(&[("spp", "4"), ("spp_max", "64")]);
        assert_eq!(p.substitute("$spp_max/$spp"), Some(Ok("64/4".to_owned())));
        assert_eq!(p.substitute("plain"), None);
        assert_eq!(p.unused().count(), 0);
    }

    #[test]
    fn defaults_do_not_override_the_caller_nor_earlier_defaults() {
        let mut p = defines(&[("res", "32")]);
        assert!(p.set_default("res", "256"));
        assert!(p.set_default("spp", "8"));
        assert!(p.set_default("spp", "9"));
        assert_eq!(p.substitute("$res $spp"), Some(Ok("32 8".to_owned())));
    }

    #[test]
    fn undefined_and_escaped_dollars() {
        let mut p = defines(&[("a", "1")]);
        assert_eq!(p.substitute("$a $b_2 x"), Some(Err(SubstituteError::Undefined("b_2".into()))));
        assert_eq!(p.substitute("\\$a costs $a"), Some(Ok("$a costs 1".to_owned())));
        assert_eq!(p.substitute("$"), Some(Err(SubstituteError::Undefined(String::new()))));
    }

    #[test]
    fn unused_caller_definitions_are_reported() {
        let mut p = defines(&[("used", "1"), ("spare", "2")]);
        let _ = p.substitute("$used");
        let unused: Vec<_> = p.unused().map(|q| q.key.as_str()).collect();
        assert_eq!(unused, ["$spare"]);
    }

    #[test]
    fn substitution_cannot_grow_without_bound() {
        let big = "x".repeat(MAX_SUBSTITUTED_BYTES / 2);
        let mut p = defines(&[("big", &big)]);
        assert_eq!(p.substitute("$big $big $big"), Some(Err(SubstituteError::TooLong)));
    }

    #[test]
    fn parameters_are_bounded() {
        let mut p = Params::default();
        for i in 0..MAX_PARAMETERS {
            assert!(p.set_default(&format!("p{i}"), "1"));
        }
        assert!(p.set_default("p0", "2"), "an existing name is no new parameter");
        assert!(!p.set_default("one_more", "1"));
    }

    #[test]
    fn define_arguments() {
        assert_eq!(parse_define("a_1=x=y"), Ok(("a_1".into(), "x=y".into())));
        assert_eq!(parse_define("empty="), Ok(("empty".into(), String::new())));
        assert!(matches!(parse_define("novalue"), Err(DefineError::NoEquals(_))));
        assert!(matches!(parse_define("=1"), Err(DefineError::BadName(_))));
        assert!(matches!(parse_define("a-b=1"), Err(DefineError::BadName(_))));
    }
}
