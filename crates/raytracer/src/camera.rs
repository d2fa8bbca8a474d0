//! The course camera (spec section 3, `camera`), with an optional thin lens, and the parallel
//! projection of Mitsuba's `orthographic` sensor ([`CameraSettings::orthographic`]).
//!
//! `right = unit(N x z)` (or `x` when `N` is vertical), `up = right x N`; the image plane sits at
//! distance 1 along `N` and spans `lens_W x lens_H`. Pixel coordinates used here are continuous:
//! `x` from 0 at the left edge to `width` at the right, `y` from 0 at the **top** to `height` at
//! the bottom (image order); the course's row index counts from the bottom, so row `i` of the spec
//! is `y = height - i - 0.5` at its centre.

use std::f64::consts::TAU;

use glam::DVec3;

use crate::geometry::Ray;
use crate::scene::CameraSettings;

/// A camera ready to generate rays for an image of a given size.
#[derive(Clone, Debug)]
pub struct Camera {
    eye: DVec3,
    forward: DVec3,
    /// `right * lens_W / 2`.
    half_width: DVec3,
    /// `up * lens_H / 2`.
    half_height: DVec3,
    right: DVec3,
    up: DVec3,
    width: f64,
    height: f64,
    /// Lens radius; 0 for a pinhole.
    aperture: f64,
    /// Distance along `forward` of the plane in focus.
    focal_distance: f64,
    /// Parallel rays along `forward` from the plane through `eye`; the half vectors are then
    /// half the visible rectangle.
    orthographic: bool,
    /// The image's centre on the image plane relative to `forward` (or to `eye`, orthographic):
    /// `right * window_offset.0 + up * window_offset.1`.
    centre: DVec3,
}

impl Camera {
    /// The camera of `settings` for a `width x height` image. `focal_distance` is used when the
    /// settings have a lens but no `focal_dist=`.
    pub fn new(settings: &CameraSettings, width: u32, height: u32, focal_distance: f64) -> Camera {
        let forward = settings.dir;
        let right = forward.cross(settings.up.unwrap_or(DVec3::Z)).try_normalize().unwrap_or(DVec3::X);
        let up = right.cross(forward);
        Camera {
            eye: settings.eye,
            forward,
            half_width: right * (settings.lens_width / 2.0),
            half_height: up * (settings.lens_height / 2.0),
            right,
            up,
            width: width as f64,
            height: height as f64,
            aperture: settings.aperture,
            focal_distance: settings.focal_distance.unwrap_or(focal_distance),
            orthographic: settings.orthographic,
            centre: right * settings.window_offset.0 + up * settings.window_offset.1,
        }
    }

    /// The image's width and height in pixels.
    pub fn image_size(&self) -> (f64, f64) {
        (self.width, self.height)
    }

    /// Whether the camera has a lens (depth of field).
    pub fn has_lens(&self) -> bool {
        self.aperture > 0.0
    }

    /// The ray through image point `(x, y)` (see the module notes), with `lens` a uniform point
    /// of the unit square choosing where on the lens the ray starts (ignored for a pinhole).
    #[inline]
    pub fn ray(&self, x: f64, y: f64, lens: (f64, f64)) -> Ray {
        let sx = 2.0 * x / self.width - 1.0;
        let sy = 1.0 - 2.0 * y / self.height;
        if self.orthographic {
            return Ray::new(
                self.eye + self.centre + self.half_height * sy + self.half_width * sx,
                self.forward,
            );
        }
        let dir = self.forward + self.centre + self.half_height * sy + self.half_width * sx;
        if self.aperture <= 0.0 {
            return Ray::new(self.eye, dir);
        }
        // Thin lens: every ray through this image point meets at the focal plane.
        let focus = self.eye + dir * self.focal_distance;
        let r = self.aperture * lens.0.sqrt();
        let phi = TAU * lens.1;
        let origin = self.eye + self.right * (r * phi.cos()) + self.up * (r * phi.sin());
        Ray::new(origin, focus - origin)
    }

    /// The ray through the image centre (for focusing).
    pub fn central_ray(&self) -> Ray {
        Ray::new(self.eye, self.forward)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn course_camera() -> CameraSettings {
        CameraSettings { dir: DVec3::Y, lens_width: 1.0, lens_height: 0.6, ..CameraSettings::default() }
    }

    #[test]
    fn centre_pixel_looks_along_n() {
        let cam = Camera::new(&course_camera(), 100, 60, 1.0);
        let ray = cam.ray(50.0, 30.0, (0.0, 0.0));
        assert!((ray.dir - DVec3::Y).length() < 1e-12);
    }

    #[test]
    fn corners_follow_the_spec_formula() {
        // Row i = 0 is the bottom: image y = H. Column j = 0 is the left: x = 0.
        let cam = Camera::new(&course_camera(), 100, 60, 1.0);
        let bottom_left = cam.ray(0.0, 60.0, (0.0, 0.0));
        let expected = DVec3::new(-0.5, 1.0, -0.3).normalize();
        assert!((bottom_left.dir - expected).length() < 1e-12, "{:?}", bottom_left.dir);
        // right = N x z = y x z = +x, up = right x N = x x y = +z.
        let top_right = cam.ray(100.0, 0.0, (0.0, 0.0));
        assert!((top_right.dir - DVec3::new(0.5, 1.0, 0.3).normalize()).length() < 1e-12);
    }

    #[test]
    fn vertical_view_uses_x_as_right() {
        let settings = CameraSettings { dir: -DVec3::Z, ..CameraSettings::default() };
        let cam = Camera::new(&settings, 10, 10, 1.0);
        let ray = cam.ray(10.0, 5.0, (0.0, 0.0));
        assert!(ray.dir.x > 0.0 && ray.dir.y.abs() < 1e-12);
    }

    #[test]
    fn orthographic_rays_are_parallel_and_cover_the_rectangle() {
        let settings = CameraSettings {
            eye: DVec3::new(1.0, -2.0, 0.5),
            lens_width: 4.0,
            lens_height: 3.0,
            orthographic: true,
            ..course_camera()
        };
        let cam = Camera::new(&settings, 40, 30, 1.0);
        let centre = cam.ray(20.0, 15.0, (0.0, 0.0));
        assert!((centre.origin - settings.eye).length() < 1e-12 && (centre.dir - DVec3::Y).length() < 1e-12);
        // Top right: right = +x, up = +z, half the rectangle from the centre.
        let corner = cam.ray(40.0, 0.0, (0.5, 0.5));
        assert!((corner.origin - DVec3::new(3.0, -2.0, 2.0)).length() < 1e-12, "{:?}", corner.origin);
        assert!((corner.dir - DVec3::Y).length() < 1e-12);
    }

    #[test]
    fn thin_lens_rays_meet_at_the_focal_plane() {
        let settings = CameraSettings { aperture: 0.1, focal_distance: Some(4.0), ..course_camera() };
        let cam = Camera::new(&settings, 100, 60, 1.0);
        let a = cam.ray(20.0, 10.0, (0.9, 0.1));
        let b = cam.ray(20.0, 10.0, (0.3, 0.7));
        assert_ne!(a.origin, b.origin);
        let ta = (4.0 - a.origin.y) / a.dir.y;
        let tb = (4.0 - b.origin.y) / b.dir.y;
        assert!((a.at(ta) - b.at(tb)).length() < 1e-9);
    }
}
