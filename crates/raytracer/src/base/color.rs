//! Colour arithmetic on linear sRGB (Rec. 709 primaries), the ray tracer's colour space.

use glam::DVec3;

/// The luminance of a linear sRGB colour (Rec. 709 weights, as Mitsuba's `luminance`).
#[inline]
pub fn luminance(c: DVec3) -> f64 {
    0.212671 * c.x + 0.715160 * c.y + 0.072169 * c.z
}

/// The mean of a colour's three channels (the course's and the photon map's measure of a
/// colour's strength).
#[inline]
pub fn channel_mean(c: DVec3) -> f64 {
    (c.x + c.y + c.z) / 3.0
}
