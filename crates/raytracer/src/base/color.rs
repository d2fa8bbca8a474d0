//! Colour arithmetic on linear sRGB (Rec. 709 primaries), the ray tracer's colour space.

use glam::DVec3;

/// The luminance of a linear sRGB colour (Rec. 709 weights, as Mitsuba's `luminance`).
#[inline]
pub fn luminance(c: DVec3) -> f64 {
    0.212671 * c.x + 0.715160 * c.y + 0.072169 * c.z
}
