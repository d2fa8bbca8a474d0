//! The fly camera: a pure state machine fed with input (held movement keys, mouse motion,
//! scroll) and elapsed time. World convention: y-up.
//!
//! Motion is smooth and independent of the frame rate: while a key is held the velocity
//! approaches its capped target exponentially, and eases back to rest when released. The
//! velocity and displacement over a step are integrated exactly, so one step of 0.1 s moves the
//! camera exactly as far as ten steps of 0.01 s.

use glam::{Mat4, Vec3, Vec4};

/// Where the camera is and where it looks.
///
/// Yaw is in degrees about the y axis: 0 looks toward -z, 90 toward +x (turning right seen from
/// above). Pitch is in degrees above the horizon, limited to [`MAX_PITCH_DEGREES`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CameraPose {
    /// Position in world units.
    pub position: Vec3,
    /// Heading in degrees: 0 toward -z, 90 toward +x.
    pub yaw_degrees: f32,
    /// Elevation of the view in degrees: positive looks up.
    pub pitch_degrees: f32,
}

/// Largest pitch up or down, in degrees (the view never flips over the vertical).
pub const MAX_PITCH_DEGREES: f32 = 89.0;
/// Narrowest field of view the scroll wheel zooms to, in degrees.
pub const MIN_FIELD_OF_VIEW_DEGREES: f32 = 1.0;
/// Widest field of view the scroll wheel zooms to, in degrees.
pub const MAX_FIELD_OF_VIEW_DEGREES: f32 = 90.0;

impl CameraPose {
    /// A pose at `position` with the given yaw and pitch (degrees; pitch is clamped).
    pub fn new(position: Vec3, yaw_degrees: f32, pitch_degrees: f32) -> Self {
        Self {
            position,
            yaw_degrees,
            pitch_degrees: pitch_degrees.clamp(-MAX_PITCH_DEGREES, MAX_PITCH_DEGREES),
        }
    }

    /// Unit vector the camera looks along.
    pub fn forward(&self) -> Vec3 {
        let (yaw, pitch) = (self.yaw_degrees.to_radians(), self.pitch_degrees.to_radians());
        Vec3::new(yaw.sin() * pitch.cos(), pitch.sin(), -yaw.cos() * pitch.cos())
    }

    /// Unit vector to the camera's right, horizontal.
    pub fn right(&self) -> Vec3 {
        let yaw = self.yaw_degrees.to_radians();
        Vec3::new(yaw.cos(), 0.0, yaw.sin())
    }

    /// World-to-camera matrix (right-handed, looking down the camera's -z).
    pub fn view_matrix(&self) -> Mat4 {
        glam::camera::rh::view::look_to_mat4(self.position, self.forward(), Vec3::Y)
    }
}

/// Why a text is not a camera pose.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum PoseSyntaxError {
    /// Not five comma-separated values.
    #[error("expected five comma-separated numbers x,y,z,yaw,pitch, found {0} value(s)")]
    Count(usize),
    /// A value is not a finite number.
    #[error("`{0}` is not a finite number")]
    Number(String),
    /// The pitch is beyond the vertical limit.
    #[error(
        "pitch {0} is out of range: it must be between -{MAX_PITCH_DEGREES} and {MAX_PITCH_DEGREES} degrees"
    )]
    Pitch(String),
}

impl std::str::FromStr for CameraPose {
    type Err = PoseSyntaxError;

    /// Parses `x,y,z,yaw,pitch`: a position in world units, then yaw and pitch in degrees.
    fn from_str(text: &str) -> Result<Self, Self::Err> {
        let parts: Vec<&str> = text.split(',').map(str::trim).collect();
        let [x, y, z, yaw, pitch] = parts[..] else {
            return Err(PoseSyntaxError::Count(parts.len()));
        };
        let number = |part: &str| {
            part.parse::<f32>()
                .ok()
                .filter(|value| value.is_finite())
                .ok_or_else(|| PoseSyntaxError::Number(part.to_string()))
        };
        let pitch_degrees = number(pitch)?;
        if pitch_degrees.abs() > MAX_PITCH_DEGREES {
            return Err(PoseSyntaxError::Pitch(pitch.to_string()));
        }
        Ok(CameraPose::new(Vec3::new(number(x)?, number(y)?, number(z)?), number(yaw)?, pitch_degrees))
    }
}

/// A perspective projection.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Lens {
    /// Vertical field of view in degrees.
    pub field_of_view_degrees: f32,
    /// Near clipping distance in world units.
    pub near: f32,
    /// Far clipping distance in world units.
    pub far: f32,
}

impl Lens {
    /// Camera-to-clip matrix for a target of the given width / height, with wgpu's depth range
    /// 0 (near) to 1 (far).
    pub fn projection(&self, aspect: f32) -> Mat4 {
        // wgpu's clip space is DirectX's: depth 0..1, y up.
        glam::camera::rh::proj::directx::perspective(
            self.field_of_view_degrees.to_radians(),
            aspect,
            self.near,
            self.far,
        )
    }
}

/// The six planes bounding what a camera sees, for culling.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Frustum {
    /// Planes as (normal, offset): a point p is inside when `normal.dot(p) + offset >= 0` for all.
    planes: [Vec4; 6],
}

impl Frustum {
    /// The frustum of a world-to-clip matrix with wgpu's depth range 0..1.
    pub fn from_view_projection(matrix: Mat4) -> Self {
        let (r0, r1, r2, r3) = (matrix.row(0), matrix.row(1), matrix.row(2), matrix.row(3));
        // Gribb and Hartmann: -w <= x <= w, -w <= y <= w, 0 <= z <= w.
        Self { planes: [r3 + r0, r3 - r0, r3 + r1, r3 - r1, r2, r3 - r2] }
    }

    /// Whether the axis-aligned box from `min` to `max` may be visible (conservative: a box near
    /// a corner may be reported visible although it is not).
    pub fn intersects_box(&self, min: Vec3, max: Vec3) -> bool {
        self.planes.iter().all(|plane| {
            // The box corner furthest along the plane's normal.
            let normal = plane.truncate();
            let corner = Vec3::select(normal.cmpge(Vec3::ZERO), max, min);
            normal.dot(corner) + plane.w >= 0.0
        })
    }
}

/// A direction of motion bound to a key.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Motion {
    /// Along the view direction (W).
    Forward,
    /// Against the view direction (S).
    Back,
    /// To the camera's left, horizontally (A, Left arrow).
    Left,
    /// To the camera's right, horizontally (D, Right arrow).
    Right,
    /// Up in world y (Up arrow).
    Up,
    /// Down in world y (Down arrow).
    Down,
}

impl Motion {
    const ALL: [Motion; 6] =
        [Motion::Forward, Motion::Back, Motion::Left, Motion::Right, Motion::Up, Motion::Down];

    fn index(self) -> usize {
        self as usize
    }
}

/// How the camera responds to input.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct MotionSettings {
    /// Top speed while a movement key is held, in world units per second.
    pub max_speed: f32,
    /// Factor on the top speed while the boost (Shift) is held.
    pub boost_factor: f32,
    /// Time constant of acceleration and braking, in seconds: after this long the velocity has
    /// covered 63% of the way to its target.
    pub response_seconds: f32,
    /// Turn per pixel of mouse motion, in degrees.
    pub degrees_per_pixel: f32,
    /// Change of the field of view per scroll-wheel line, in degrees.
    pub zoom_degrees_per_line: f32,
}

impl Default for MotionSettings {
    fn default() -> Self {
        Self {
            max_speed: 3.0,
            boost_factor: 4.0,
            response_seconds: 0.25,
            degrees_per_pixel: 0.12,
            zoom_degrees_per_line: 2.0,
        }
    }
}

/// Where the camera may go: a box, and a minimum height above the ground under it.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Limits {
    /// Lowest corner of the allowed box, in world units.
    pub min: Vec3,
    /// Highest corner of the allowed box, in world units.
    pub max: Vec3,
    /// Smallest height above the ground (terrain or water), in world units.
    pub clearance: f32,
}

impl Limits {
    /// No limits at all.
    pub const NONE: Limits =
        Limits { min: Vec3::splat(f32::NEG_INFINITY), max: Vec3::splat(f32::INFINITY), clearance: 0.0 };

    /// The nearest allowed point to `position`: inside the box and at least `clearance` above
    /// the ground, `ground(x, z)` giving the terrain height there (`None` off the terrain, where
    /// the ground is `min.y`). Where the box is too low for the clearance, its ceiling wins.
    pub fn clamp(&self, position: Vec3, ground: impl Fn(f32, f32) -> Option<f32>) -> Vec3 {
        let horizontal = position.clamp(self.min, self.max);
        let floor =
            ground(horizontal.x, horizontal.z).map_or(self.min.y, |h| h.max(self.min.y)) + self.clearance;
        let min = Vec3::new(self.min.x, floor.min(self.max.y), self.min.z);
        position.clamp(min, self.max)
    }
}

/// The camera a user flies: pose, field of view, velocity and the keys being held.
#[derive(Debug, Clone, PartialEq)]
pub struct FlyCamera {
    pose: CameraPose,
    field_of_view_degrees: f32,
    velocity: Vec3,
    held: [bool; 6],
    boost: bool,
    settings: MotionSettings,
}

impl FlyCamera {
    /// A camera at rest at `pose` with a vertical field of view in degrees (clamped to 1..=90).
    pub fn new(pose: CameraPose, field_of_view_degrees: f32, settings: MotionSettings) -> Self {
        Self {
            pose: CameraPose::new(pose.position, pose.yaw_degrees, pose.pitch_degrees),
            field_of_view_degrees: field_of_view_degrees
                .clamp(MIN_FIELD_OF_VIEW_DEGREES, MAX_FIELD_OF_VIEW_DEGREES),
            velocity: Vec3::ZERO,
            held: [false; 6],
            boost: false,
            settings,
        }
    }

    /// The current pose.
    pub fn pose(&self) -> CameraPose {
        self.pose
    }

    /// The current vertical field of view, in degrees.
    pub fn field_of_view_degrees(&self) -> f32 {
        self.field_of_view_degrees
    }

    /// The current velocity, in world units per second.
    pub fn velocity(&self) -> Vec3 {
        self.velocity
    }

    /// Presses (`held = true`) or releases a movement key.
    pub fn set_held(&mut self, motion: Motion, held: bool) {
        self.held[motion.index()] = held;
    }

    /// Presses or releases the boost (faster top speed).
    pub fn set_boost(&mut self, boost: bool) {
        self.boost = boost;
    }

    /// Releases every key (e.g. when the window loses focus).
    pub fn release_all(&mut self) {
        self.held = [false; 6];
        self.boost = false;
    }

    /// Turns the view by a mouse motion in pixels: right turns right, down looks down. The pitch
    /// stays within [`MAX_PITCH_DEGREES`].
    pub fn turn(&mut self, dx_pixels: f64, dy_pixels: f64) {
        let scale = f64::from(self.settings.degrees_per_pixel);
        let yaw = ((f64::from(self.pose.yaw_degrees) + dx_pixels * scale).rem_euclid(360.0)) as f32;
        let pitch = f64::from(self.pose.pitch_degrees) - dy_pixels * scale;
        // Rounding to f32 can land exactly on 360.
        self.pose.yaw_degrees = if yaw >= 360.0 { 0.0 } else { yaw };
        self.pose.pitch_degrees = (pitch as f32).clamp(-MAX_PITCH_DEGREES, MAX_PITCH_DEGREES);
    }

    /// Zooms by scroll-wheel lines: positive (wheel away from the user) narrows the field of
    /// view. It stays within 1..=90 degrees.
    pub fn zoom(&mut self, lines: f32) {
        self.field_of_view_degrees = (self.field_of_view_degrees
            - lines * self.settings.zoom_degrees_per_line)
            .clamp(MIN_FIELD_OF_VIEW_DEGREES, MAX_FIELD_OF_VIEW_DEGREES);
    }

    /// The velocity the held keys ask for, in world units per second.
    pub fn target_velocity(&self) -> Vec3 {
        let direction = |motion: Motion| match motion {
            Motion::Forward => self.pose.forward(),
            Motion::Back => -self.pose.forward(),
            Motion::Left => -self.pose.right(),
            Motion::Right => self.pose.right(),
            Motion::Up => Vec3::Y,
            Motion::Down => -Vec3::Y,
        };
        let wish: Vec3 = Motion::ALL
            .iter()
            .filter(|motion| self.held[motion.index()])
            .map(|&motion| direction(motion))
            .sum();
        let speed = self.settings.max_speed * if self.boost { self.settings.boost_factor } else { 1.0 };
        wish.normalize_or_zero() * speed
    }

    /// Advances the camera by `seconds` (negative or non-finite steps are ignored), then keeps it
    /// within `limits`, `ground(x, z)` giving the terrain height there (`None` off the terrain,
    /// where the ground is `limits.min.y`).
    pub fn update(&mut self, seconds: f32, limits: &Limits, ground: impl Fn(f32, f32) -> Option<f32>) {
        if !(seconds.is_finite() && seconds > 0.0) {
            return;
        }
        let target = self.target_velocity();
        // Exact solution of dv/dt = (target - v) / tau over the step.
        let tau = self.settings.response_seconds.max(1e-4);
        let decay = (-seconds / tau).exp();
        let excess = self.velocity - target;
        let displacement = target * seconds + excess * tau * (1.0 - decay);
        self.velocity = target + excess * decay;
        self.pose.position += displacement;
        self.keep_within(limits, ground);
    }

    fn keep_within(&mut self, limits: &Limits, ground: impl Fn(f32, f32) -> Option<f32>) {
        let p = self.pose.position;
        let clamped = limits.clamp(p, ground);
        // Stop moving into a wall instead of pressing against it.
        for axis in 0..3 {
            if clamped[axis] != p[axis] {
                self.velocity[axis] = 0.0;
            }
        }
        self.pose.position = clamped;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn camera() -> FlyCamera {
        FlyCamera::new(CameraPose::new(Vec3::new(0.0, 2.5, 10.0), 0.0, 0.0), 45.0, MotionSettings::default())
    }

    fn run(camera: &mut FlyCamera, seconds: f32, steps: u32) {
        for _ in 0..steps {
            camera.update(seconds / steps as f32, &Limits::NONE, |_, _| None);
        }
    }

    #[test]
    fn directions_follow_yaw_and_pitch() {
        let pose = CameraPose::new(Vec3::ZERO, 0.0, 0.0);
        assert!(pose.forward().abs_diff_eq(-Vec3::Z, 1e-6));
        assert!(pose.right().abs_diff_eq(Vec3::X, 1e-6));
        let turned = CameraPose::new(Vec3::ZERO, 90.0, 0.0);
        assert!(turned.forward().abs_diff_eq(Vec3::X, 1e-6));
        let up = CameraPose::new(Vec3::ZERO, 0.0, 30.0);
        assert!((up.forward().y - 0.5).abs() < 1e-6);
        // The view matrix puts the forward direction on the camera's -z axis.
        let seen = pose.view_matrix().transform_vector3(pose.forward());
        assert!(seen.abs_diff_eq(-Vec3::Z, 1e-6));
    }

    #[test]
    fn frustum_keeps_what_is_in_view() {
        let pose = CameraPose::new(Vec3::new(0.0, 2.0, 10.0), 0.0, 0.0);
        let lens = Lens { field_of_view_degrees: 45.0, near: 0.1, far: 100.0 };
        let frustum = Frustum::from_view_projection(lens.projection(16.0 / 9.0) * pose.view_matrix());
        let unit = Vec3::splat(0.5);
        let seen = |centre: Vec3| frustum.intersects_box(centre - unit, centre + unit);
        assert!(seen(Vec3::new(0.0, 2.0, 0.0)), "ahead");
        assert!(!seen(Vec3::new(0.0, 2.0, 20.0)), "behind");
        assert!(!seen(Vec3::new(50.0, 2.0, 0.0)), "far to the right");
        assert!(!seen(Vec3::new(0.0, 2.0, -200.0)), "beyond the far plane");
        assert!(seen(Vec3::new(0.0, 2.0, 10.0)), "around the camera");
        // A long box crossing the view is seen although its corners are all outside.
        assert!(frustum.intersects_box(Vec3::new(-100.0, 1.5, -5.0), Vec3::new(100.0, 2.5, -4.0)));
    }

    #[test]
    fn parses_poses() {
        let pose: CameraPose = "1, 2.5,-3,90,-10".parse().expect("valid");
        assert_eq!(pose, CameraPose::new(Vec3::new(1.0, 2.5, -3.0), 90.0, -10.0));
        assert_eq!("1,2,3".parse::<CameraPose>(), Err(PoseSyntaxError::Count(3)));
        assert_eq!("1,2,3,4,x".parse::<CameraPose>(), Err(PoseSyntaxError::Number("x".into())));
        assert_eq!("1,2,inf,4,0".parse::<CameraPose>(), Err(PoseSyntaxError::Number("inf".into())));
        assert_eq!("0,0,0,0,95".parse::<CameraPose>(), Err(PoseSyntaxError::Pitch("95".into())));
    }

    #[test]
    fn accelerates_smoothly_to_a_capped_speed() {
        let mut cam = camera();
        cam.set_held(Motion::Forward, true);
        let mut last_speed = 0.0;
        for _ in 0..20 {
            run(&mut cam, 0.05, 1);
            let speed = cam.velocity().length();
            assert!(speed > last_speed, "speed must grow while the key is held");
            assert!(speed <= 3.0 + 1e-4, "speed {speed} above the cap");
            last_speed = speed;
        }
        // After 4 time constants the speed is within 2% of the cap.
        assert!(last_speed > 3.0 * 0.98, "{last_speed}");
        assert!(cam.pose().position.z < 10.0, "moved toward -z");
    }

    #[test]
    fn decelerates_smoothly_when_released() {
        let mut cam = camera();
        cam.set_held(Motion::Right, true);
        run(&mut cam, 2.0, 40);
        cam.set_held(Motion::Right, false);
        let released_at = cam.pose().position.x;
        let mut last = cam.velocity().length();
        for _ in 0..40 {
            run(&mut cam, 0.05, 1);
            let speed = cam.velocity().length();
            assert!(speed < last);
            last = speed;
        }
        assert!(last < 0.01, "still moving at {last}");
        // Coasting distance is speed * tau.
        let coast = cam.pose().position.x - released_at;
        assert!((coast - 3.0 * 0.25).abs() < 0.02, "coasted {coast}");
    }

    #[test]
    fn motion_does_not_depend_on_the_frame_rate() {
        let (mut coarse, mut fine) = (camera(), camera());
        for cam in [&mut coarse, &mut fine] {
            cam.set_held(Motion::Forward, true);
            cam.set_held(Motion::Up, true);
        }
        run(&mut coarse, 0.6, 3);
        run(&mut fine, 0.6, 600);
        assert!(
            coarse.pose().position.abs_diff_eq(fine.pose().position, 1e-4),
            "{:?} vs {:?}",
            coarse.pose().position,
            fine.pose().position
        );
        assert!(coarse.velocity().abs_diff_eq(fine.velocity(), 1e-4));
    }

    proptest::proptest! {
        #[test]
        fn any_frame_timing_gives_the_same_motion(
            steps in proptest::collection::vec(0.001f32..0.2, 1..60),
            yaw in 0.0f32..360.0,
            pitch in -80.0f32..80.0,
        ) {
            let start = CameraPose::new(Vec3::new(1.0, 2.0, 3.0), yaw, pitch);
            let mut uneven = FlyCamera::new(start, 45.0, MotionSettings::default());
            let mut single = uneven.clone();
            for cam in [&mut uneven, &mut single] {
                cam.set_held(Motion::Forward, true);
                cam.set_held(Motion::Right, true);
            }
            let total: f32 = steps.iter().sum();
            for &step in &steps {
                uneven.update(step, &Limits::NONE, |_, _| None);
            }
            single.update(total, &Limits::NONE, |_, _| None);
            let (a, b) = (uneven.pose().position, single.pose().position);
            proptest::prop_assert!(a.abs_diff_eq(b, 1e-3 * (1.0 + total)), "{a:?} vs {b:?}");
            proptest::prop_assert!(uneven.velocity().length() <= 3.0 + 1e-4);
        }
    }

    #[test]
    fn diagonal_keys_do_not_exceed_the_cap_and_boost_raises_it() {
        let mut cam = camera();
        cam.set_held(Motion::Forward, true);
        cam.set_held(Motion::Left, true);
        assert!((cam.target_velocity().length() - 3.0).abs() < 1e-5);
        cam.set_boost(true);
        assert!((cam.target_velocity().length() - 12.0).abs() < 1e-4);
        cam.set_held(Motion::Forward, false);
        cam.set_held(Motion::Left, false);
        cam.set_held(Motion::Up, true);
        cam.set_held(Motion::Down, true);
        assert_eq!(cam.target_velocity(), Vec3::ZERO);
    }

    #[test]
    fn pitch_and_zoom_stay_in_range() {
        let mut cam = camera();
        cam.turn(0.0, -10_000.0);
        assert_eq!(cam.pose().pitch_degrees, MAX_PITCH_DEGREES);
        cam.turn(0.0, 20_000.0);
        assert_eq!(cam.pose().pitch_degrees, -MAX_PITCH_DEGREES);
        cam.turn(3000.0, 0.0);
        assert!((0.0..360.0).contains(&cam.pose().yaw_degrees));
        cam.zoom(1000.0);
        assert_eq!(cam.field_of_view_degrees(), MIN_FIELD_OF_VIEW_DEGREES);
        cam.zoom(-1000.0);
        assert_eq!(cam.field_of_view_degrees(), MAX_FIELD_OF_VIEW_DEGREES);
        cam.zoom(0.5);
        assert_eq!(cam.field_of_view_degrees(), MAX_FIELD_OF_VIEW_DEGREES - 1.0);
    }

    #[test]
    fn stays_within_limits_and_above_the_ground() {
        let mut cam = camera();
        let limits =
            Limits { min: Vec3::new(-5.0, 0.0, -5.0), max: Vec3::new(5.0, 4.0, 11.0), clearance: 0.2 };
        cam.set_held(Motion::Down, true);
        for _ in 0..100 {
            cam.update(0.05, &limits, |x, _| (x.abs() < 1.0).then_some(1.0));
        }
        assert!((cam.pose().position.y - 1.2).abs() < 1e-5, "{:?}", cam.pose());
        assert_eq!(cam.velocity().y, 0.0);
        cam.set_held(Motion::Down, false);
        cam.set_held(Motion::Right, true);
        for _ in 0..100 {
            cam.update(0.05, &limits, |x, _| (x.abs() < 1.0).then_some(1.0));
        }
        let p = cam.pose().position;
        assert_eq!(p.x, 5.0);
        // Off the raised ground, only the water clearance holds it up... once it sinks.
        assert!(p.y >= 0.2 - 1e-6);
    }

    #[test]
    fn clamps_points_into_the_box_and_above_the_ground() {
        let limits =
            Limits { min: Vec3::new(-5.0, 0.0, -5.0), max: Vec3::new(5.0, 4.0, 11.0), clearance: 0.2 };
        let hill = |x: f32, _: f32| (x.abs() < 1.0).then_some(1.0);
        let inside = Vec3::new(2.0, 3.0, 0.0);
        assert_eq!(limits.clamp(inside, hill), inside);
        // Under the water, and inside the hill.
        assert_eq!(limits.clamp(Vec3::new(3.0, -2.0, 0.0), hill), Vec3::new(3.0, 0.2, 0.0));
        assert_eq!(limits.clamp(Vec3::new(0.5, 0.5, 0.0), hill), Vec3::new(0.5, 1.2, 0.0));
        // Outside the box: the ground is taken where the point ends up, not where it was.
        assert_eq!(limits.clamp(Vec3::new(-0.5, 9.0, 50.0), hill), Vec3::new(-0.5, 4.0, 11.0));
        assert_eq!(
            limits.clamp(Vec3::new(-30.0, 0.1, 0.0), |x, _| (x > -6.0).then_some(1.0)),
            Vec3::new(-5.0, 1.2, 0.0)
        );
    }

    #[test]
    fn ignores_bad_time_steps() {
        let mut cam = camera();
        cam.set_held(Motion::Forward, true);
        let before = cam.clone();
        for step in [0.0, -1.0, f32::NAN, f32::INFINITY] {
            cam.update(step, &Limits::NONE, |_, _| None);
        }
        assert_eq!(cam, before);
    }
}
