//! The typed key reader: a closed block's entries read as numbers, vectors, colours, integers
//! and text, each problem reported at its key or value.

use glam::DVec3;

use super::blocks::{BEZIER_POINT_KEY, BlockKind, Entry, OpenBlock, Parser, PrimitiveKind, known_keys};
use crate::base::diagnostic::{Diagnostic, clip};
use crate::base::error::GeometryError;
use crate::base::source::Span;

/// A key's value could not be used; the error has been reported.
#[derive(Debug)]
pub(super) struct Reported;

/// The result of looking up a key: absent, present and valid, or present and invalid (already
/// reported).
pub(super) type Lookup<T> = Result<Option<T>, Reported>;

/// Reads typed values out of a finished block, reporting problems.
pub(super) struct BlockReader<'p, 's> {
    pub(super) kind: BlockKind,
    pub(super) header: Span,
    /// The last entry of each key (later lines win), in file order of their first line.
    pub(super) entries: Vec<Entry<'s>>,
    /// Whether each entry was read.
    pub(super) used: smallvec::SmallVec<[bool; 32]>,
    /// The control points of a `primitive bezier` block (`P=` lines), in file order.
    pub(super) points: Vec<Entry<'s>>,
    pub(super) parser: &'p mut Parser<'s>,
}

impl<'p, 's> BlockReader<'p, 's> {
    pub(super) fn new(block: OpenBlock<'s>, parser: &'p mut Parser<'s>) -> Self {
        let bezier = block.kind == BlockKind::Primitive(PrimitiveKind::Bezier);
        let (points, entries): (Vec<Entry<'s>>, Vec<Entry<'s>>) = if bezier {
            block.entries.into_iter().partition(|e| e.key == BEZIER_POINT_KEY)
        } else {
            (Vec::new(), block.entries)
        };
        let used = smallvec::smallvec![false; entries.len()];
        BlockReader { kind: block.kind, header: block.header, entries, used, points, parser }
    }

    /// The position of the entry of `key`, if the block has one.
    pub(super) fn position(&self, key: &str) -> Option<usize> {
        // The first bytes compared before the whole keys: most keys differ there.
        let first = key.as_bytes().first();
        self.entries.iter().position(|e| e.key.as_bytes().first() == first && e.key == key)
    }

    /// The entry of `key`, if the block has one.
    pub(super) fn find(&self, key: &str) -> Option<&Entry<'s>> {
        self.position(key).map(|i| &self.entries[i])
    }

    /// Whether the block sets `key=`.
    pub(super) fn has(&self, key: &str) -> bool {
        self.find(key).is_some()
    }

    /// The entry of `key`, marked as used.
    pub(super) fn entry(&mut self, key: &str) -> Option<Entry<'s>> {
        let i = self.position(key)?;
        self.used[i] = true;
        Some(self.entries[i].clone())
    }

    pub(super) fn span_of(&self, key: &str) -> Span {
        self.find(key).map_or(self.header, Entry::values_span)
    }

    pub(super) fn error(&mut self, span: Span, message: impl Into<String>) -> &mut Diagnostic {
        self.parser.error(span, message)
    }

    pub(super) fn warning(&mut self, span: Span, message: impl Into<String>) -> &mut Diagnostic {
        self.parser.warning(span, message)
    }

    /// Parses the `N` numbers of `key`.
    pub(super) fn numbers<const N: usize>(&mut self, key: &str) -> Lookup<[f64; N]> {
        let Some(i) = self.position(key) else { return Ok(None) };
        self.used[i] = true;
        let what = || if N == 1 { "a number".to_owned() } else { format!("{N} numbers") };
        let entry = &self.entries[i];
        if entry.value_count != N {
            let found = entry.value_count;
            let span = entry.values_span();
            let message = if found == 0 {
                format!("`{key}=` expects {}", what())
            } else {
                format!(
                    "`{key}=` expects {}, found {found} value{}",
                    what(),
                    if found == 1 { "" } else { "s" }
                )
            };
            self.error(span, message);
            return Err(Reported);
        }
        let mut out = [0.0; N];
        let mut bad = false;
        let values: [(&str, Span); N] = std::array::from_fn(|k| self.entries[i].values[k]);
        for (slot, (text, span)) in out.iter_mut().zip(values) {
            match text.parse::<f64>() {
                Ok(v) if v.is_finite() => *slot = v,
                Ok(_) => {
                    self.error(span, format!("`{}` is not a finite number", clip(text)));
                    bad = true;
                }
                Err(_) => {
                    self.error(
                        span,
                        format!("`{key}=` expects {}; `{}` is not a number", what(), clip(text)),
                    );
                    bad = true;
                }
            }
        }
        if bad { Err(Reported) } else { Ok(Some(out)) }
    }

    pub(super) fn number(&mut self, key: &str) -> Lookup<f64> {
        Ok(self.numbers::<1>(key)?.map(|[v]| v))
    }

    pub(super) fn vec3(&mut self, key: &str) -> Lookup<DVec3> {
        Ok(self.numbers::<3>(key)?.map(DVec3::from_array))
    }

    /// A whole number in `min..=max`.
    pub(super) fn integer(&mut self, key: &str, min: u64, max: u64) -> Lookup<u64> {
        let Some(v) = self.number(key)? else { return Ok(None) };
        if v.fract() != 0.0 || v < min as f64 || v > max as f64 {
            let span = self.span_of(key);
            self.error(span, format!("`{key}=` must be a whole number from {min} to {max}, not {v}"));
            return Err(Reported);
        }
        Ok(Some(v as u64))
    }

    /// The raw text after `key=` (for words and paths, which may contain spaces).
    pub(super) fn text(&mut self, key: &str) -> Lookup<(String, Span)> {
        let Some(entry) = self.entry(key) else { return Ok(None) };
        if entry.value_count == 0 {
            self.error(entry.key_span, format!("`{key}=` needs a value"));
            return Err(Reported);
        }
        let span = entry.values_span();
        let line = self.parser.source.line(span.line);
        let text: String = line.chars().skip(span.column as usize - 1).take(span.len as usize).collect();
        Ok(Some((text, span)))
    }

    /// A required value: reports a missing key at the block header.
    pub(super) fn required<T>(&mut self, key: &str, value: Lookup<T>, meaning: &str) -> Option<T> {
        match value {
            Ok(Some(v)) => Some(v),
            Ok(None) => {
                let header = self.header;
                self.error(header, format!("`{}` needs `{key}=` ({meaning})", self.kind));
                None
            }
            Err(Reported) => None,
        }
    }

    /// A required vector (see [`BlockReader::required`]).
    pub(super) fn required_vec3(&mut self, key: &str, meaning: &str) -> Option<DVec3> {
        let value = self.vec3(key);
        self.required(key, value, meaning)
    }

    /// A required number (see [`BlockReader::required`]).
    pub(super) fn required_number(&mut self, key: &str, meaning: &str) -> Option<f64> {
        let value = self.number(key);
        self.required(key, value, meaning)
    }

    /// A weight that should not be negative; negative values are kept, with a warning.
    pub(super) fn weight(&mut self, key: &str) -> f64 {
        match self.number(key) {
            Ok(Some(v)) => {
                if v < 0.0 {
                    let span = self.span_of(key);
                    self.warning(span, format!("`{key}=` is negative"));
                }
                v
            }
            _ => 0.0,
        }
    }

    /// A colour; components outside [0, 1] get a warning unless `lights` (light colours may
    /// exceed 1).
    pub(super) fn color(&mut self, key: &str, allow_bright: bool) -> Lookup<DVec3> {
        let c = self.vec3(key)?;
        if let Some(c) = c {
            let out_of_range = c.min_element() < 0.0 || (!allow_bright && c.max_element() > 1.0);
            if out_of_range {
                let span = self.span_of(key);
                let range = if allow_bright { "not be negative" } else { "lie in [0, 1]" };
                self.warning(span, format!("colour components of `{key}=` should {range}"));
            }
        }
        Ok(c)
    }

    pub(super) fn geometry_error(&mut self, err: GeometryError) {
        let key = match &err {
            GeometryError::NonPositiveRadius(_) => "R",
            GeometryError::ZeroVector(k)
            | GeometryError::ParallelAxes(k, _)
            | GeometryError::TooLarge(k)
            | GeometryError::TooSmall(k) => k,
            GeometryError::ZeroAxis | GeometryError::AxisTooLong | GeometryError::AxisTooShort => "O2",
            GeometryError::Degenerate(_) | GeometryError::ControlPoints(_) => "",
        };
        let span = self.span_of(key);
        let kind = self.kind;
        self.error(span, format!("in `{kind}`, {err}"));
    }

    /// The constructed value, or `None` after reporting why it could not be built.
    pub(super) fn built<T>(&mut self, value: Result<T, GeometryError>) -> Option<T> {
        value.map_err(|e| self.geometry_error(e)).ok()
    }

    /// Warns about keys the block does not know.
    pub(super) fn finish(self) {
        let BlockReader { kind, mut entries, used, parser, .. } = self;
        let mut unknown: Vec<&Entry> =
            entries.iter().zip(&used).filter(|(_, u)| !**u).map(|(e, _)| e).collect();
        unknown.sort_by_key(|e| (e.key_span.line, e.key_span.column));
        for e in unknown {
            let known = known_keys(kind);
            let d =
                parser.warning(e.key_span, format!("unknown key `{}=` in `{kind}`; ignored", clip(e.key)));
            if let Some(k) = known.iter().find(|k| k.eq_ignore_ascii_case(e.key)) {
                d.notes.push(format!("did you mean `{k}=`? keys are case-sensitive"));
            } else {
                d.notes.push(format!(
                    "`{kind}` knows {}",
                    known.iter().map(|k| format!("`{k}=`")).collect::<Vec<_>>().join(", ")
                ));
            }
        }
        entries.clear();
        parser.spare_entries = entries;
    }
}
