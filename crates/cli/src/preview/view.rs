//! How the preview shows its image: zoom and pan (window pixels per image pixel, and where the
//! image's top-left corner is in the window) and the exposure. Pure state, no window.

/// Smallest zoom (window pixels per image pixel).
pub const MIN_ZOOM: f64 = 1.0 / 64.0;
/// Largest zoom.
pub const MAX_ZOOM: f64 = 64.0;
/// Zoom factor of one scroll-wheel line.
pub const ZOOM_PER_LINE: f64 = 1.25;
/// Exposure range, in stops either way.
pub const MAX_EXPOSURE_STOPS: i32 = 16;

/// The view of the image in the window.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct View {
    /// Window pixels per image pixel.
    pub zoom: f64,
    /// Where the image's top-left corner is, in window pixels from the window's top-left.
    pub offset: [f64; 2],
    /// Exposure in stops: the linear values are multiplied by `2^stops` before display.
    pub exposure_stops: i32,
}

impl View {
    /// The image (`image` pixels) centred in a window of `window` pixels, at 1:1 when it fits,
    /// else as large as fits.
    pub fn fit(image: (u32, u32), window: (u32, u32)) -> View {
        let (iw, ih) = (f64::from(image.0.max(1)), f64::from(image.1.max(1)));
        let (ww, wh) = (f64::from(window.0.max(1)), f64::from(window.1.max(1)));
        let zoom = (ww / iw).min(wh / ih).min(1.0).clamp(MIN_ZOOM, MAX_ZOOM);
        View {
            zoom,
            offset: [((ww - iw * zoom) / 2.0).round(), ((wh - ih * zoom) / 2.0).round()],
            exposure_stops: 0,
        }
    }

    /// Zooms by `lines` wheel lines (positive: closer) keeping the image point under `cursor`
    /// (window pixels) where it is. Crossing 1:1 stops at 1:1, so every zoom level is reached.
    pub fn zoom_at(&mut self, cursor: [f64; 2], lines: f64) {
        let old = self.zoom;
        let mut zoom = (old * ZOOM_PER_LINE.powf(lines)).clamp(MIN_ZOOM, MAX_ZOOM);
        if (old < 1.0 && zoom > 1.0) || (old > 1.0 && zoom < 1.0) {
            zoom = 1.0;
        }
        let scale = zoom / old;
        for (offset, at) in self.offset.iter_mut().zip(cursor) {
            *offset = at - (at - *offset) * scale;
        }
        self.zoom = zoom;
    }

    /// Moves the image by `delta` window pixels.
    pub fn pan(&mut self, delta: [f64; 2]) {
        self.offset[0] += delta[0];
        self.offset[1] += delta[1];
    }

    /// One stop brighter (`up`) or darker, within [`MAX_EXPOSURE_STOPS`].
    pub fn step_exposure(&mut self, up: bool) {
        let step = if up { 1 } else { -1 };
        self.exposure_stops = (self.exposure_stops + step).clamp(-MAX_EXPOSURE_STOPS, MAX_EXPOSURE_STOPS);
    }

    /// The factor on linear values, `2^stops`.
    pub fn exposure_scale(&self) -> f32 {
        2f32.powi(self.exposure_stops)
    }

    /// The image pixel under `cursor` (window pixels), if the cursor is on the image.
    pub fn pixel_at(&self, cursor: [f64; 2], image: (u32, u32)) -> Option<(u32, u32)> {
        let x = ((cursor[0] - self.offset[0]) / self.zoom).floor();
        let y = ((cursor[1] - self.offset[1]) / self.zoom).floor();
        let inside = x >= 0.0 && y >= 0.0 && x < f64::from(image.0) && y < f64::from(image.1);
        inside.then_some((x as u32, y as u32))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_small_image_starts_at_one_to_one_centred_and_a_large_one_fits() {
        let v = View::fit((100, 50), (300, 150));
        assert_eq!((v.zoom, v.offset), (1.0, [100.0, 50.0]));
        let v = View::fit((1000, 500), (500, 500));
        assert_eq!(v.zoom, 0.5);
        assert_eq!(v.pixel_at([0.0, 125.0], (1000, 500)), Some((0, 0)));
        assert_eq!(v.pixel_at([0.0, 124.0], (1000, 500)), None);
    }

    #[test]
    fn zoom_keeps_the_point_under_the_cursor_and_stops_at_one_to_one() {
        let mut v = View::fit((100, 100), (100, 100));
        let cursor = [30.5, 70.5];
        let before = v.pixel_at(cursor, (100, 100));
        v.zoom_at(cursor, 3.0);
        assert!((v.zoom - 1.25f64.powi(3)).abs() < 1e-12);
        assert_eq!(v.pixel_at(cursor, (100, 100)), before);
        v.zoom_at(cursor, -10.0);
        assert_eq!(v.zoom, 1.0, "zooming out from above 1:1 stops at 1:1");
        v.zoom_at(cursor, -1000.0);
        assert_eq!(v.zoom, MIN_ZOOM);
        v.zoom_at(cursor, 1000.0);
        assert_eq!(v.zoom, 1.0);
        v.zoom_at(cursor, 1000.0);
        assert_eq!(v.zoom, MAX_ZOOM);
    }

    #[test]
    fn pan_and_exposure_steps() {
        let mut v = View::fit((10, 10), (10, 10));
        v.pan([3.0, -2.0]);
        assert_eq!(v.pixel_at([3.0, 0.0], (10, 10)), Some((0, 2)));
        v.step_exposure(true);
        v.step_exposure(true);
        v.step_exposure(false);
        assert_eq!(v.exposure_scale(), 2.0);
        for _ in 0..100 {
            v.step_exposure(false);
        }
        assert_eq!(v.exposure_stops, -MAX_EXPOSURE_STOPS);
    }
}
