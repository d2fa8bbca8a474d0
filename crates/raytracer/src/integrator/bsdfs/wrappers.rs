//! The wrapper plugins, `twosided`, `mask` and `blendbsdf` (Mitsuba 3's `twosided.cpp`,
//! `mask.cpp`, `blendbsdf.cpp`), flattened into weighted components.
//!
//! Every wrapper is linear in its nested BSDFs once its parameters are evaluated, so a tree of
//! wrappers is a weighted sum of leaf lobes, each admitted on one side of the surface:
//! - `blendbsdf`: `(1 - w) first + w second` (`w` clamped to [0, 1]);
//! - `mask`: `o material + (1 - o) null` (`o`, the opacity, clamped to [0, 1]), the null lobe
//!   passing light straight through (`wi = -wo`, weight 1, as Mitsuba);
//! - `twosided`: `front` when `wo.z > 0`; when `wo.z < 0`, `back` with both directions'
//!   `z` negated (seen as from its front); nothing at `wo.z = 0`.
//!
//! For any `wo` the weights of the admitted components sum to 1 (or less when components are
//! beyond [`MAX_COMPONENTS`]), so sampling chooses a component with probability its weight.

use glam::DVec3;

use super::{Lobe, leaf_lobe};
use crate::material::{Material, Param};

/// The most components a [`super::PhysicalBsdf`] holds: the scene builder refuses materials
/// with more ([`Material::component_count`]).
pub const MAX_COMPONENTS: usize = crate::material::MAX_COMPONENTS;

/// The side of the surface on which `wo` must lie for a component to act.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Side {
    /// Either side.
    Any,
    /// `wo.z > 0`.
    Front,
    /// `wo.z < 0`.
    Back,
}

impl Side {
    /// Whether `wo` is on this side.
    #[inline]
    pub fn admits(self, wo: DVec3) -> bool {
        match self {
            Side::Any => true,
            Side::Front => wo.z > 0.0,
            Side::Back => wo.z < 0.0,
        }
    }
}

/// A weighted lobe of a flattened BSDF.
#[derive(Clone, Debug, PartialEq)]
pub struct Component {
    /// The weight, in (0, 1].
    pub weight: f64,
    /// Where `wo` must be for the component to act.
    pub side: Side,
    /// Whether the lobe sees directions with `z` negated (the back of a `twosided`).
    pub flip: bool,
    /// The lobe.
    pub lobe: Lobe,
}

impl Component {
    /// A direction in the lobe's frame (or back: the map is its own inverse).
    #[inline]
    pub fn to_lobe(&self, w: DVec3) -> DVec3 {
        if self.flip { DVec3::new(w.x, w.y, -w.z) } else { w }
    }

    /// `(wo, wi)` in the lobe's frame, or `None` when the component does not act for `wo`.
    #[inline]
    pub fn localise(&self, wo: DVec3, wi: DVec3) -> Option<(DVec3, DVec3)> {
        if self.side.admits(wo) { Some((self.to_lobe(wo), self.to_lobe(wi))) } else { None }
    }
}

/// The number of components `material` flattens to ([`Material::component_count`]).
pub fn component_count(material: &Material) -> usize {
    material.component_count()
}

/// The frame a subtree is reached in: its weight, the side `wo` must be on (in the BSDF's
/// frame) and whether `z` is negated.
#[derive(Clone, Copy)]
struct Reach {
    weight: f64,
    side: Side,
    flip: bool,
}

/// Calls `out` with every component of `material` of nonzero weight, in a fixed order.
pub(super) fn flatten(
    material: &Material,
    param: &mut dyn FnMut(&Param) -> DVec3,
    out: &mut dyn FnMut(Component),
) {
    walk(material, Reach { weight: 1.0, side: Side::Any, flip: false }, param, out);
}

fn walk(
    material: &Material,
    at: Reach,
    param: &mut dyn FnMut(&Param) -> DVec3,
    out: &mut dyn FnMut(Component),
) {
    if at.weight <= 0.0 || at.weight.is_nan() {
        return;
    }
    match material {
        Material::Course(_) => {}
        Material::TwoSided { front, back } => {
            // In the current frame, front needs z > 0, back z < 0 (then seen flipped).
            let (front_side, back_side) =
                if at.flip { (Side::Back, Side::Front) } else { (Side::Front, Side::Back) };
            if let Some(side) = meet(at.side, front_side) {
                walk(front, Reach { side, ..at }, param, out);
            }
            if let Some(side) = meet(at.side, back_side) {
                walk(back, Reach { side, flip: !at.flip, ..at }, param, out);
            }
        }
        Material::Mask { opacity, material } => {
            let o = clamp01(param(opacity).x);
            walk(material, Reach { weight: at.weight * o, ..at }, param, out);
            let w = at.weight * (1.0 - o);
            if w > 0.0 {
                out(Component { weight: w, side: at.side, flip: at.flip, lobe: Lobe::Null });
            }
        }
        Material::Blend { weight, first, second } => {
            let t = clamp01(param(weight).x);
            walk(first, Reach { weight: at.weight * (1.0 - t), ..at }, param, out);
            walk(second, Reach { weight: at.weight * t, ..at }, param, out);
        }
        // The frame is perturbed by the integrator (outermost level only).
        Material::Perturbed { material, .. } => walk(material, at, param, out),
        leaf => {
            if let Some(lobe) = leaf_lobe(leaf, param) {
                out(Component { weight: at.weight, side: at.side, flip: at.flip, lobe });
            }
        }
    }
}

/// Both side conditions at once, or `None` when they exclude each other.
fn meet(a: Side, b: Side) -> Option<Side> {
    match (a, b) {
        (Side::Any, s) | (s, Side::Any) => Some(s),
        (a, b) if a == b => Some(a),
        _ => None,
    }
}

fn clamp01(x: f64) -> f64 {
    if x.is_nan() { 0.0 } else { x.clamp(0.0, 1.0) }
}
